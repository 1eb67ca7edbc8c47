"""The camera calibration file: one fisheye camera as JSON.

``vmnav calibrate`` writes it; the robot, the simulator and the tools read it.
Example (the default camera, :meth:`CameraModel.default`)::

    {
      "format": "vmnav-camera",
      "format_version": 1,
      "model": "omnidir-mei",
      "image_size": [800, 600],
      "K": [[451.60, 0.0, 399.5], [0.0, 451.60, 299.5], [0.0, 0.0, 1.0]],
      "xi": 1.6,
      "D": [0.0, 0.0, 0.0, 0.0],
      "fov_deg": 185.0,
      "rms_px": null,
      "source": "CameraModel.default()"
    }

Fields (all required; no others are allowed):

``format``
    The string ``"vmnav-camera"``.
``format_version``
    The integer 1. Readers refuse versions they do not know.
``model``
    ``"omnidir-mei"``: the unified sphere model of Mei and Rives (ICRA 2007) with
    radial-tangential distortion, exactly as ``cv2.omnidir`` defines it (see
    :mod:`shared.camera_model` for the equations).
``image_size``
    ``[width, height]`` of the images the calibration is for, px, positive integers.
``K``
    The camera matrix ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]``, px, row-major:
    focal lengths fx, fy > 0, skew s, principal point (cx, cy) in OpenCV's pixel
    convention (the centre of the top-left pixel is (0, 0)).
``xi``
    The sphere-to-plane offset, dimensionless, >= 0 (0 is a pinhole camera).
``D``
    Distortion ``[k1, k2, p1, p2]`` on the normalised plane, dimensionless.
``fov_deg``
    Full field of view of the lens, degrees, in (0, 360): rays more than
    ``fov_deg / 2`` off the optical axis are invalid. Calibration cannot measure it;
    it comes from the lens data sheet.
``rms_px``
    Root-mean-square reprojection error of the calibration, px, or ``null``
    (e.g. a camera written by hand).
``source``
    Free text saying where the calibration came from, or ``null``.

Numbers must be finite (JSON has no NaN, and this reader refuses the
``NaN``/``Infinity`` extensions). Writes are atomic: a temporary file in the same
directory is renamed over the target, so readers see the old file or the new one.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from shared.atomic_file import write_text_atomic
from shared.camera_model import CameraModel
from shared.errors import CalibrationError
from shared.json_file import parse_json

FORMAT = "vmnav-camera"
FORMAT_VERSION = 1
MODEL = "omnidir-mei"

_FIELDS = (
    "format",
    "format_version",
    "model",
    "image_size",
    "K",
    "xi",
    "D",
    "fov_deg",
    "rms_px",
    "source",
)


def read_camera(path: str | Path) -> CameraModel:
    """Read and validate a camera calibration file.

    Args:
        path: the JSON file.

    Returns:
        The camera.

    Raises:
        CalibrationError: the file is missing, unreadable, not JSON, or any field
            is missing, unknown, of the wrong type or shape, or out of range; the
            message names the file and the field.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CalibrationError(path, "file not found") from None
    except (OSError, UnicodeDecodeError) as e:
        raise CalibrationError(path, f"cannot read: {e}") from None
    return camera_from_dict(parse_json(path, text, CalibrationError), path)


def load_camera(path: str | None) -> CameraModel:
    """The camera from a calibration file, or the default camera when ``path`` is None."""
    if path is None:
        return CameraModel.default()
    return read_camera(path)


def write_camera(
    path: str | Path,
    camera: CameraModel,
    *,
    rms_px: float | None = None,
    source: str | None = None,
) -> None:
    """Write a camera calibration file atomically.

    The content is validated exactly as :func:`read_camera` would before anything
    touches the disk, so an existing file is never replaced by one that cannot be
    read back.

    Args:
        path: the JSON file to create or replace.
        camera: the camera.
        rms_px: reprojection RMS error of the calibration, px, if known.
        source: where the calibration came from, free text.

    Raises:
        CalibrationError: the camera cannot be stored (e.g. non-finite numbers);
            names the file, which is left untouched.
        InputError: the file cannot be written (see :mod:`shared.atomic_file`).
    """
    path = Path(path)
    data = camera_to_dict(camera, rms_px=rms_px, source=source)
    try:
        camera_from_dict(data, path)
    except CalibrationError as e:
        raise CalibrationError(path, f"refusing to write an invalid camera: {e.problem}") from None
    # One field per line, each value compact: K reads as a matrix.
    fields = (f"  {json.dumps(key)}: {json.dumps(value)}" for key, value in data.items())
    text = "{\n" + ",\n".join(fields) + "\n}\n"
    write_text_atomic(path, text)


def check_replaceable(path: str | Path, writer: str) -> None:
    """Fail unless ``path`` is absent or a calibration file that ``writer`` wrote.

    A tool that writes calibrations calls this before its work, so that a typo in
    ``--out`` cannot replace an image, a config or a calibration made by hand.

    Args:
        path: the file about to be written.
        writer: what the ``source`` field of the tool's files starts with
            (e.g. ``"vmnav calibrate"``).

    Raises:
        CalibrationError: the file exists and is not such a calibration; names it.
    """
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        return
    refusal = f"exists and was not written by {writer}: not replacing it (move it away first)"
    # A calibration is a few hundred bytes: a big file is something else, left unread.
    if not path.is_file() or path.stat().st_size > 1 << 16:
        raise CalibrationError(path, refusal)
    try:
        data = parse_json(path, path.read_text(encoding="utf-8"), CalibrationError)
    except (CalibrationError, OSError, UnicodeDecodeError):
        raise CalibrationError(path, refusal) from None
    if not isinstance(data, Mapping):
        raise CalibrationError(path, refusal)
    source = data.get("source")
    if not (data.get("format") == FORMAT and isinstance(source, str)
            and source.startswith(writer)):
        raise CalibrationError(path, refusal)


def camera_to_dict(
    camera: CameraModel, *, rms_px: float | None = None, source: str | None = None
) -> dict[str, Any]:
    """The JSON object of a camera calibration (see the module docstring).

    Returned for embedding in other files (e.g. a visual-memory manifest); the
    values are plain Python numbers, lists and strings.
    """
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "model": MODEL,
        "image_size": [int(camera.width), int(camera.height)],
        "K": [[float(x) for x in row] for row in camera.K],
        "xi": float(camera.xi),
        "D": [float(x) for x in camera.D],
        "fov_deg": float(camera.fov_deg),
        "rms_px": None if rms_px is None else float(rms_px),
        "source": source,
    }


def camera_from_dict(data: Any, where: str | Path) -> CameraModel:
    """Validate a parsed calibration object and build the camera.

    Args:
        data: the parsed JSON value.
        where: the file (or ``file: key``) it came from, for messages.

    Returns:
        The camera.

    Raises:
        CalibrationError: ``"<where>: <field>: <problem>"``.
    """
    if not isinstance(data, Mapping):
        raise CalibrationError(where, f"expected a JSON object, got {_describe(data)}")
    unknown = sorted(set(data) - set(_FIELDS))
    if unknown:
        raise CalibrationError(where, f"unknown field {unknown[0]!r}")
    for name in _FIELDS:
        if name not in data:
            raise CalibrationError(where, f"missing field {name!r}")

    if data["format"] != FORMAT:
        raise CalibrationError(where, f"format: expected {FORMAT!r}, got {data['format']!r}")
    version = data["format_version"]
    if not _is_int(version):
        raise CalibrationError(
            where, f"format_version: expected an integer, got {_describe(version)}"
        )
    if version != FORMAT_VERSION:
        raise CalibrationError(
            where, f"format_version {version} is not supported (this vmnav reads {FORMAT_VERSION})"
        )
    if data["model"] != MODEL:
        raise CalibrationError(where, f"model: expected {MODEL!r}, got {data['model']!r}")

    size = data["image_size"]
    if not (isinstance(size, list) and len(size) == 2 and all(_is_int(v) and v > 0 for v in size)):
        raise CalibrationError(
            where,
            f"image_size: expected [width, height], two positive integers, got {_describe(size)}",
        )
    if not (isinstance(data["K"], list) and len(data["K"]) == 3):
        raise CalibrationError(
            where, f"K: expected 3 rows of 3 numbers, got {_describe(data['K'])}"
        )
    K = [_numbers(row, f"K[{i}]", 3, where) for i, row in enumerate(data["K"])]
    if K[0][0] <= 0.0 or K[1][1] <= 0.0:
        raise CalibrationError(where, f"K: fx and fy must be > 0, got fx={K[0][0]}, fy={K[1][1]}")
    if K[1][0] != 0.0 or K[2] != [0.0, 0.0, 1.0]:
        raise CalibrationError(
            where, f"K: rows 2 and 3 must be [0, fy, cy] and [0, 0, 1], got {K[1]} and {K[2]}"
        )
    (cx, cy), (width, height) = (K[0][2], K[1][2]), size
    if not (0.0 <= cx <= width - 1 and 0.0 <= cy <= height - 1):
        raise CalibrationError(
            where, f"K: the principal point ({cx:g}, {cy:g}) px is outside the {width}x{height} "
            "image (cx and cy are pixel coordinates of the optical axis)")
    xi = _number(data["xi"], "xi", where)
    if xi < 0.0:
        raise CalibrationError(where, f"xi: must be >= 0, got {xi}")
    D = _numbers(data["D"], "D", 4, where)
    fov_deg = _number(data["fov_deg"], "fov_deg", where)
    if not 0.0 < fov_deg < 360.0:
        raise CalibrationError(where, f"fov_deg: must be in (0, 360) degrees, got {fov_deg}")
    if data["rms_px"] is not None:
        rms_px = _number(data["rms_px"], "rms_px", where)
        if rms_px < 0.0:
            raise CalibrationError(where, f"rms_px: must be >= 0 or null, got {rms_px}")
    if data["source"] is not None and not isinstance(data["source"], str):
        raise CalibrationError(
            where, f"source: expected a string or null, got {_describe(data['source'])}"
        )
    return CameraModel(width=size[0], height=size[1], K=K, xi=xi, D=D, fov_deg=fov_deg)


def check_image_size(camera: CameraModel, width: int, height: int, where: str | Path) -> None:
    """Fail unless ``camera`` was calibrated for ``width x height`` images.

    Args:
        camera: the camera.
        width: image width, px.
        height: image height, px.
        where: the calibration file (or whatever holds the camera), for the message.

    Raises:
        CalibrationError: e.g. ``"camera.json: calibration is for 800x600 but
            images are 640x480"``.
    """
    if (camera.width, camera.height) != (width, height):
        raise CalibrationError(
            where,
            f"calibration is for {camera.width}x{camera.height} but images are {width}x{height}",
        )


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any, name: str, where: str | Path) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CalibrationError(where, f"{name}: expected a number, got {_describe(value)}")
    if not math.isfinite(value):
        raise CalibrationError(where, f"{name}: expected a finite number, got {value}")
    return float(value)


def _numbers(value: Any, name: str, length: int, where: str | Path) -> list[float]:
    """A JSON array of ``length`` finite numbers."""
    if not (isinstance(value, list) and len(value) == length):
        raise CalibrationError(where, f"{name}: expected {length} numbers, got {_describe(value)}")
    return [_number(x, name, where) for x in value]


_JSON_TYPES = {
    type(None): "null",
    bool: "a boolean",
    int: "an integer",
    float: "a number",
    str: "a string",
    list: "an array",
    dict: "an object",
}


def _describe(value: Any) -> str:
    """E.g. ``an array [1, 2]``, with long values cut short."""
    if value is None:
        return "null"
    text = json.dumps(value) if type(value) in _JSON_TYPES else repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{_JSON_TYPES.get(type(value), type(value).__name__)} {text}"
