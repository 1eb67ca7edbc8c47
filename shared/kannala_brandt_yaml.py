"""Reading an equidistant (Kannala-Brandt) camera calibration from its YAML file.

The layout is Kalibr's and Kimera-VIO's sensor file, in OpenCV's YAML dialect
(``%YAML:1.0``, read with ``cv2.FileStorage``)::

    T_BS:                       # optional: body <- sensor, 4x4 row-major
      cols: 4
      rows: 4
      data: [r11, r12, r13, tx, ..., 0, 0, 0, 1]
    resolution: [752, 480]      # width, height, px
    camera_model: pinhole       # optional; pinhole if given
    intrinsics: [fu, fv, cu, cv]                  # px
    distortion_model: equidistant                 # optional; equidistant if given
    distortion_coefficients: [k1, k2, k3, k4]

``T_BS`` may also be an ``!!opencv-matrix`` (the same map with a ``dt`` key). Other keys
(``camera_id``, ``rate_hz``...) are ignored. Every problem is one line naming the file
and the key.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from shared.errors import CalibrationError
from shared.kannala_brandt import KannalaBrandtCamera

FloatArray = npt.NDArray[np.float64]

#: Largest calibration file read, bytes.
MAX_YAML_BYTES = 1 << 20
#: Largest deviation of T_BS's rotation block from a rotation (|R^T R - I|, max entry).
ROTATION_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class EquidistantCalibration:
    """One camera's calibration file.

    Attributes:
        camera: the equidistant camera.
        T_body_sensor: (4, 4) float64 pose of the camera in the body frame
            (``X_body = T X_sensor``, m), or None if the file has no ``T_BS``.
    """

    camera: KannalaBrandtCamera
    T_body_sensor: FloatArray | None


def read_equidistant_yaml(path: str | Path) -> EquidistantCalibration:
    """Read and check an equidistant calibration file (module docstring).

    Raises:
        CalibrationError: missing or unreadable file, not OpenCV YAML, a missing key,
            a value of the wrong type, size or range; one line naming file and key.
    """
    import cv2

    path = Path(path)
    try:
        with path.open("rb") as file:
            data = file.read(MAX_YAML_BYTES + 1)
    except FileNotFoundError:
        raise CalibrationError(path, "file not found") from None
    except OSError as e:
        raise CalibrationError(path, f"cannot read: {e.strerror}") from None
    if len(data) > MAX_YAML_BYTES:
        raise CalibrationError(path, f"more than {MAX_YAML_BYTES} bytes: not a calibration")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise CalibrationError(path, f"not UTF-8 text (byte {e.start})") from None
    if not text.strip():
        raise CalibrationError(path, "empty file")
    flags = cv2.FILE_STORAGE_READ | cv2.FILE_STORAGE_MEMORY | cv2.FILE_STORAGE_FORMAT_YAML
    try:
        storage = cv2.FileStorage(text, flags)  # its nodes live as long as it does
    except (cv2.error, SystemError) as e:
        # OpenCV's parser raises cv2.error, which its binding wraps in a SystemError.
        cause = e.__cause__ if isinstance(e.__cause__, cv2.error) else e
        detail = str(cause).strip().splitlines()[-1].split("in function '")[-1].rstrip("'")
        at_line = re.search(r"\((\d+)\): (.*)$", detail)
        if at_line:
            detail = f"line {at_line[1]}: {at_line[2]}"
        raise CalibrationError(path, f"not OpenCV YAML: {detail}") from None
    root = storage.root()
    if not root.isMap():
        raise CalibrationError(path, "not a YAML map of keys")
    keys = set(root.keys())

    def need(key: str) -> Any:
        if key not in keys:
            raise CalibrationError(path, f"missing key {key!r}")
        return root.getNode(key)

    for key, expected in (("camera_model", "pinhole"), ("distortion_model", "equidistant")):
        if key in keys and root.getNode(key).string() != expected:
            raise CalibrationError(path, f"{key}: expected {expected!r}, got "
                                         f"{root.getNode(key).string()!r}")
    width, height = _numbers(need("resolution"), "resolution", 2, path)
    if not (width.is_integer() and height.is_integer() and width > 0 and height > 0):
        raise CalibrationError(path, f"resolution: expected two positive integers, got "
                                     f"[{width:g}, {height:g}]")
    fu, fv, cu, cv = _numbers(need("intrinsics"), "intrinsics", 4, path)
    if fu <= 0.0 or fv <= 0.0:
        raise CalibrationError(path, f"intrinsics: fu and fv must be > 0, got {fu:g}, {fv:g}")
    k = _numbers(need("distortion_coefficients"), "distortion_coefficients", 4, path)
    camera = KannalaBrandtCamera(int(width), int(height), fu, fv, cu, cv, np.array(k))
    return EquidistantCalibration(camera, _pose(root.getNode("T_BS"), path)
                                  if "T_BS" in keys else None)


def _numbers(node: Any, key: str, n: int, path: Path) -> list[float]:
    """``n`` finite numbers from a YAML sequence node."""
    if not node.isSeq() or node.size() != n:
        raise CalibrationError(path, f"{key}: expected a list of {n} numbers")
    values = []
    for i in range(n):
        item = node.at(i)
        if not (item.isInt() or item.isReal()) or not math.isfinite(item.real()):
            raise CalibrationError(path, f"{key}[{i}]: expected a finite number")
        values.append(float(item.real()))
    return values


def _pose(node: Any, path: Path) -> FloatArray:
    """A rigid 4x4 transform from a ``{rows: 4, cols: 4, data: [16 numbers]}`` map."""
    if not node.isMap() or not {"rows", "cols", "data"} <= set(node.keys()):
        raise CalibrationError(path, "T_BS: expected a map with rows, cols and data")
    shape = (node.getNode("rows").real(), node.getNode("cols").real())
    if shape != (4.0, 4.0):
        raise CalibrationError(path, f"T_BS: expected 4 rows and 4 cols, got {shape[0]:g} "
                                     f"and {shape[1]:g}")
    T = np.array(_numbers(node.getNode("data"), "T_BS: data", 16, path)).reshape(4, 4)
    R = T[:3, :3]
    if (np.abs(R.T @ R - np.eye(3)).max() > ROTATION_TOLERANCE or np.linalg.det(R) <= 0.0
            or not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0])):
        raise CalibrationError(path, "T_BS: not a rigid transform (rotation block not a "
                                     "rotation, or last row not [0, 0, 0, 1])")
    return T
