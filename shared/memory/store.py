"""A visual memory on disk: a versioned manifest plus three files per key image.

Layout::

    DIR/manifest.json         the graph, the metadata and the camera (below)
    DIR/images/<id>.png       the key image, 8-bit grey, the camera's size
    DIR/features/<id>.npz     pixels_xy (N, 2) float64 px, patches (N, P*P) float32, and
                              tracked_from_previous (K, 2) int64 (optional when reading:
                              memories written before it load with none); no pickle
    DIR/thumbnails/<id>.png   80x60 8-bit grey (shared.memory.keyframe.thumbnail_from_image)

Manifest (all fields required, no others allowed)::

    {
     "format": "vmnav-memory",
     "format_version": 2,
     "camera": {... shared.calibration.camera_to_dict ...},
     "front_end": "orb, 31 px window",
     "paths": [{"id": 0, "name": "corridor", "keyframe_ids": [0, 1, 2]}],
     "keyframes": [{"id": 0, "path_id": 0, "index": 0, "t_ns": 0,
                    "odom_pose": [0.0, 0.0, 0.0], "distance_m": 0.0}, ...],
     "junctions": [{"from_id": 2, "to_id": 7, "matches": 85}]
    }

``odom_pose`` is ``[x_m, y_m, yaw_rad]`` in the path's teach odometry frame;
``distance_m`` the odometric distance from the path's first key image, m.
``front_end`` names what described the key images' points (``VisualMemory.front_end``:
a memory's descriptors are compared only with descriptors of the same kind), or is
null when unknown. Format version 1 (before ``front_end``) is read as unknown.

Rules of writing (an interrupted write never leaves a memory that fails to load,
nor one that loads with the wrong content):

1. Writes only add. :func:`write_memory` refuses to drop or change a key image,
   path or junction that ``DIR`` already holds, or to change its camera or a front end
   it records (an unknown one may become known).
2. Data files first, manifest last. The data files written are those of key
   images the current manifest does not list, so their names are fresh: no
   manifest on disk refers to them until the new manifest replaces the old one
   (``os.replace`` via :mod:`shared.atomic_file`; each file is fsynced first).
   A write cut short leaves unreferenced files, which the next write replaces.

Reading validates everything and raises
:class:`~shared.errors.MemoryFormatError` naming the file and the problem.
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from shared.atomic_file import write_bytes_atomic, write_text_atomic
from shared.calibration import camera_from_dict, camera_to_dict
from shared.camera_model import CameraModel
from shared.errors import CalibrationError, InputError, MemoryFormatError
from shared.image_decode import check_image
from shared.json_file import parse_json
from shared.memory._npz import ArraySpec, read_npz
from shared.memory.graph import VisualMemory
from shared.memory.keyframe import (
    THUMBNAIL_HEIGHT_PX,
    THUMBNAIL_WIDTH_PX,
    GreyImage,
    Junction,
    Keyframe,
    KeyframeRecord,
    Patches,
    PixelsXY,
    Tracks,
    VisualPath,
    check_features,
    check_grey_image,
    check_tracks,
    thumbnail_from_image,
)

FORMAT = "vmnav-memory"
FORMAT_VERSION = 2
READ_VERSIONS = (1, 2)
"""Format versions this vmnav reads (1: without ``front_end``)."""
MANIFEST_NAME = "manifest.json"

_FIELDS = ("format", "format_version", "camera", "front_end", "paths", "keyframes", "junctions")
_FIELDS_V1 = tuple(f for f in _FIELDS if f != "front_end")
_MAX_FRONT_END_CHARS = 200
_PATH_FIELDS = ("id", "name", "keyframe_ids")
_KEYFRAME_FIELDS = ("id", "path_id", "index", "t_ns", "odom_pose", "distance_m")
_JUNCTION_FIELDS = ("from_id", "to_id", "matches")
_FEATURE_ARRAYS = ("pixels_xy", "patches")
MAX_FEATURES_BYTES = 64 * 2**20
"""The most a features file's arrays may hold together, uncompressed, bytes; one key
image's 300 corners with 11x11 patches hold 150 kB."""
_FILE_OVERHEAD_BYTES = 64 * 2**10
"""Room for a file's own structure (zip directory and headers, PNG chunks), bytes."""
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Every PNG ends with an empty IEND chunk: its type and its (constant) CRC.
_PNG_END = b"IEND\xaeB`\x82"


def image_path(directory: str | Path, keyframe_id: int) -> Path:
    """Where the key image ``keyframe_id`` of the memory in ``directory`` is stored."""
    return Path(directory) / "images" / f"{keyframe_id}.png"


def features_path(directory: str | Path, keyframe_id: int) -> Path:
    """Where the corners and descriptors of key image ``keyframe_id`` are stored."""
    return Path(directory) / "features" / f"{keyframe_id}.npz"


def thumbnail_path(directory: str | Path, keyframe_id: int) -> Path:
    """Where the thumbnail of key image ``keyframe_id`` is stored."""
    return Path(directory) / "thumbnails" / f"{keyframe_id}.png"


def read_memory(directory: str | Path) -> VisualMemory:
    """Read and validate the visual memory stored in ``directory``.

    Raises:
        MemoryFormatError: names the file (manifest, image, features or thumbnail)
            and the problem: not found, truncated or invalid JSON, a missing or
            unknown field, an unsupported ``format_version``, an undecodable or
            empty file, an image of the wrong size or type, arrays of the wrong
            shape or dtype, pickled data, duplicate or dangling ids.
    """
    directory = Path(directory)
    manifest = _read_manifest(directory)
    camera = manifest.camera
    keyframes: list[Keyframe] = []
    for i, entry in enumerate(manifest.data["keyframes"]):
        descriptor_length = keyframes[0].descriptor_length if keyframes else None
        keyframes.append(_read_keyframe(directory, entry, i, camera, descriptor_length))
    try:
        return VisualMemory.from_parts(camera, keyframes, manifest.paths, manifest.junctions,
                                       manifest.front_end)
    except MemoryFormatError as e:
        raise MemoryFormatError(manifest.path, f"{e.where}: {e.problem}") from None


def files_without_manifest(directory: str | Path) -> int:
    """How many files ``directory`` holds, at any depth, while it has no manifest.

    A new memory started there would write its manifest over them: key images whose
    manifest was lost, another program's files, or (rule 2) a first write cut short.
    Callers that start an empty memory where :data:`MANIFEST_NAME` is missing check
    that this is 0 first.

    Returns:
        0 when ``directory`` holds a manifest, no file (empty sub-folders allowed), does
        not exist or is not a folder.
    """
    directory = Path(directory)
    if not directory.is_dir() or (directory / MANIFEST_NAME).exists():
        return 0
    return sum(len(files) for _, _, files in os.walk(directory))


def check_no_orphans(directory: str | Path) -> None:
    """Refuse to start a new memory over files whose manifest is missing
    (:func:`files_without_manifest`).

    Raises:
        MemoryFormatError: ``directory`` holds files but no manifest.
    """
    orphans = files_without_manifest(directory)
    if orphans:
        raise MemoryFormatError(f"memory {directory}", f"{MANIFEST_NAME} missing but the folder "
                                f"holds {orphans} files; restore it or point --memory to an "
                                "empty folder")


def write_memory(directory: str | Path, memory: VisualMemory) -> None:
    """Store ``memory`` in ``directory`` (created if needed), adding to what is there.

    ``directory`` may be empty or hold a memory that ``memory`` extends (e.g. was
    read from it, then given a new path and junctions); see the module docstring
    for why an interrupted write is harmless.

    Raises:
        MemoryFormatError: the memory already in ``directory`` cannot be read.
        InputError: ``directory`` holds a memory that ``memory`` does not extend
            (another camera, or a key image, path or junction it lacks or
            differs in; nothing is written then), or cannot be written (the memory
            stored before still loads).
    """
    directory = Path(directory)
    data = _manifest_from_memory(memory)
    manifest_file = directory / MANIFEST_NAME
    stored_ids: set[int] = set()
    if manifest_file.exists():
        stored = _read_manifest(directory).data
        _check_extends(manifest_file, stored, data)
        stored_ids = {entry["id"] for entry in stored["keyframes"]}
    for folder in ("images", "features", "thumbnails"):
        try:
            (directory / folder).mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(directory / folder, f"cannot create folder: {e.strerror}") from None
    for keyframe_id in sorted(set(memory.keyframes) - stored_ids):
        keyframe = memory.keyframes[keyframe_id]
        write_bytes_atomic(image_path(directory, keyframe_id), _encode_png(keyframe.image))
        write_bytes_atomic(
            features_path(directory, keyframe_id),
            _encode_features(keyframe.pixels_xy, keyframe.patches, keyframe.tracked_from_previous),
        )
        write_bytes_atomic(thumbnail_path(directory, keyframe_id), _encode_png(keyframe.thumbnail))
    write_text_atomic(manifest_file, _manifest_text(data))


def add_path_to_disk(
    directory: str | Path, camera: CameraModel, name: str, records: Sequence[KeyframeRecord]
) -> VisualPath:
    """Add a taught path to the memory in ``directory``, creating the memory if needed.

    For a path with junctions, use :func:`read_memory`, ``add_path``,
    ``add_junction`` and :func:`write_memory` instead (same guarantees).

    Args:
        directory: the memory's folder; created with an empty memory if it holds none.
        camera: the camera the records were taken with; must be the memory's.
        name: the path's name, e.g. the route taught.
        records: its key images in driving order.

    Returns:
        The new path, with its key image ids.

    Raises:
        MemoryFormatError: the stored memory cannot be read, or a record is invalid.
        InputError: the memory was taught with another camera calibration, or
            ``directory`` cannot be written.
    """
    directory = Path(directory)
    if (directory / MANIFEST_NAME).exists():
        memory = read_memory(directory)
        if camera_to_dict(memory.camera) != camera_to_dict(camera):
            raise InputError(
                directory / MANIFEST_NAME,
                "the memory was taught with another camera calibration than the one given",
            )
    else:
        memory = VisualMemory(camera)
    path = memory.add_path(name, records)
    write_memory(directory, memory)
    return path


@dataclass(frozen=True)
class _Manifest:
    path: Path
    data: dict[str, Any]  # the parsed JSON, structure checked
    camera: CameraModel
    front_end: str | None
    paths: tuple[VisualPath, ...]
    junctions: tuple[Junction, ...]


def _read_manifest(directory: Path) -> _Manifest:
    """Parse and check the manifest's structure; key image fields are checked later."""
    path = directory / MANIFEST_NAME
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        problem = "no such folder" if not directory.is_dir() else "file not found"
        raise MemoryFormatError(path, f"{problem}: not a visual memory") from None
    except (OSError, UnicodeDecodeError) as e:
        raise MemoryFormatError(path, f"cannot read: {e}") from None
    data = parse_json(path, text, MemoryFormatError)
    if not isinstance(data, dict):
        raise MemoryFormatError(path, f"expected a JSON object, got {_json_type(data)}")
    if data.get("format") != FORMAT:
        raise MemoryFormatError(path, f"format: expected {FORMAT!r}, got {data.get('format')!r}")
    version = data.get("format_version")
    if type(version) is not int or version not in READ_VERSIONS:
        raise MemoryFormatError(
            path, f"format_version {version!r} is not supported (this vmnav reads "
                  f"{' and '.join(map(str, READ_VERSIONS))})"
        )
    _check_fields(path, "", data, _FIELDS if version >= 2 else _FIELDS_V1)
    front_end = data.get("front_end")
    if front_end is not None and (not isinstance(front_end, str) or not front_end.isprintable()
                                  or not 0 < len(front_end) <= _MAX_FRONT_END_CHARS):
        raise MemoryFormatError(
            path, f"front_end: expected null or a printable text of 1-{_MAX_FRONT_END_CHARS} "
                  f"characters, got {front_end!r:.60}")
    try:
        camera = camera_from_dict(data["camera"], "camera")
    except CalibrationError as e:
        raise MemoryFormatError(path, f"{e.where}: {e.problem}") from None
    for i, entry in enumerate(_array(path, "keyframes", data["keyframes"])):
        _check_fields(path, f"keyframes[{i}]: ", entry, _KEYFRAME_FIELDS)
        keyframe_id = entry["id"]
        if not isinstance(keyframe_id, int) or isinstance(keyframe_id, bool) or keyframe_id < 0:
            raise MemoryFormatError(
                path, f"keyframes[{i}]: id: expected an integer >= 0, got {keyframe_id!r}"
            )
    paths = tuple(
        _record(path, f"paths[{i}]", VisualPath, entry, _PATH_FIELDS)
        for i, entry in enumerate(_array(path, "paths", data["paths"]))
    )
    junctions = tuple(
        _record(path, f"junctions[{i}]", Junction, entry, _JUNCTION_FIELDS)
        for i, entry in enumerate(_array(path, "junctions", data["junctions"]))
    )
    return _Manifest(path=path, data=data, camera=camera, front_end=front_end, paths=paths,
                     junctions=junctions)


def _read_keyframe(
    directory: Path,
    entry: dict[str, Any],
    position: int,
    camera: CameraModel,
    descriptor_length: int | None,
) -> Keyframe:
    keyframe_id = entry["id"]
    image = _read_png(image_path(directory, keyframe_id), (camera.height, camera.width))
    path = features_path(directory, keyframe_id)
    pixels_xy, patches, tracks = _read_features(
        path, camera.width, camera.height, descriptor_length
    )
    thumbnail = _read_png(
        thumbnail_path(directory, keyframe_id), (THUMBNAIL_HEIGHT_PX, THUMBNAIL_WIDTH_PX)
    )
    try:
        return Keyframe(
            image=image, pixels_xy=pixels_xy, patches=patches, thumbnail=thumbnail,
            tracked_from_previous=tracks, **entry
        )
    except MemoryFormatError as e:
        raise MemoryFormatError(
            directory / MANIFEST_NAME, f"keyframes[{position}]: {e.where}: {e.problem}"
        ) from None


def _read_bytes(path: Path, max_bytes: int) -> bytes:
    """The content of ``path``, refused unread if longer than ``max_bytes``."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            if size > max_bytes:
                raise MemoryFormatError(path, f"{size} bytes, more than the {max_bytes} "
                                        "allowed for this file")
            data = f.read(size + 1)  # one more: to see it growing
    except FileNotFoundError:
        raise MemoryFormatError(path, "file not found") from None
    except OSError as e:
        raise MemoryFormatError(path, f"cannot read: {e.strerror}") from None
    if not data:
        raise MemoryFormatError(path, "file is empty")
    if len(data) > size:
        raise MemoryFormatError(path, "grew while being read (is another program writing it?)")
    return data


def _read_png(path: Path, shape: tuple[int, int]) -> GreyImage:
    """An 8-bit grey PNG of ``shape`` (H, W)."""
    data = _read_bytes(path, _max_png_bytes(shape))
    if not data.startswith(_PNG_SIGNATURE):
        raise MemoryFormatError(path, "not a PNG file")
    if not data.endswith(_PNG_END):
        raise MemoryFormatError(path, "truncated PNG (it does not end with an IEND chunk)")
    check_image(data, path, error=MemoryFormatError)  # no bomb reaches the decoder
    image = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise MemoryFormatError(path, "corrupt PNG: cannot decode it")
    if image.ndim != 2:
        raise MemoryFormatError(path, f"expected a grey image, got {image.shape[2]} channels")
    check_grey_image(str(path), "image", image, shape)
    return image


def _read_features(
    path: Path, width: int, height: int, descriptor_length: int | None
) -> tuple[PixelsXY, Patches, Tracks]:
    """The arrays of a features file, every size checked against the camera's before
    anything is inflated (:mod:`shared.memory._npz`)."""
    pixels = width * height  # no image has more corners than pixels
    specs = {
        "pixels_xy": ArraySpec(np.dtype(np.float64), (None, 2), (pixels, 2)),
        "patches": ArraySpec(np.dtype(np.float32), (None, None),
                             (pixels, min(width, height) ** 2)),
        "tracked_from_previous": ArraySpec(np.dtype(np.int64), (None, 2), (pixels, 2)),
    }
    data = _read_bytes(path, MAX_FEATURES_BYTES + _FILE_OVERHEAD_BYTES)
    arrays = read_npz(path, data, specs, _FEATURE_ARRAYS, MAX_FEATURES_BYTES)
    pixels_xy, patches = arrays["pixels_xy"], arrays["patches"]
    tracks = arrays.get("tracked_from_previous", np.zeros((0, 2), dtype=np.int64))
    check_features(str(path), pixels_xy, patches, width, height, descriptor_length)
    check_tracks(str(path), tracks, pixels_xy.shape[0])
    return pixels_xy, patches, tracks


def _max_png_bytes(shape: tuple[int, int]) -> int:
    """The largest PNG file accepted for an 8-bit grey image of ``shape`` (H, W), bytes:
    twice the pixels plus 64 KiB (stored, uncompressed, it is one filter byte per row
    more than the pixels, plus 5 bytes per 64 KiB deflate block and the chunks' 12 each)."""
    return 2 * shape[0] * shape[1] + _FILE_OVERHEAD_BYTES


def thumbnail_png(image: GreyImage) -> bytes:
    """The PNG file of ``image``'s thumbnail, as ``thumbnails/<id>.png`` holds it (for a key
    image not stored yet: the robot serves those of the path it is teaching)."""
    return _encode_png(thumbnail_from_image(image))


def _encode_png(image: GreyImage) -> bytes:
    ok, buffer = cv2.imencode(".png", image)
    if not ok:
        raise MemoryFormatError("image", f"cv2 cannot encode a {image.shape} {image.dtype} PNG")
    return buffer.tobytes()


def _encode_features(pixels_xy: PixelsXY, patches: Patches, tracks: Tracks) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, pixels_xy=pixels_xy, patches=patches, tracked_from_previous=tracks)
    return buffer.getvalue()


def _manifest_from_memory(memory: VisualMemory) -> dict[str, Any]:
    keyframes = sorted(memory.keyframes.values(), key=lambda k: k.id)
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "camera": camera_to_dict(memory.camera),
        "front_end": memory.front_end,
        "paths": [
            {"id": p.id, "name": p.name, "keyframe_ids": list(p.keyframe_ids)}
            for p in sorted(memory.paths.values(), key=lambda p: p.id)
        ],
        "keyframes": [
            {
                "id": k.id,
                "path_id": k.path_id,
                "index": k.index,
                "t_ns": k.t_ns,
                "odom_pose": list(k.odom_pose),
                "distance_m": k.distance_m,
            }
            for k in keyframes
        ],
        "junctions": [
            {"from_id": j.from_id, "to_id": j.to_id, "matches": j.matches}
            for j in memory.junctions
        ],
    }


def _manifest_text(data: dict[str, Any]) -> str:
    """The manifest as JSON with one path, key image or junction per line."""
    lines = []
    for key, value in data.items():
        if key in ("paths", "keyframes", "junctions") and value:
            items = ",\n".join("  " + json.dumps(item, allow_nan=False) for item in value)
            lines.append(f" {json.dumps(key)}: [\n{items}\n ]")
        else:
            lines.append(f" {json.dumps(key)}: {json.dumps(value, allow_nan=False)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def _check_extends(where: Path, stored: dict[str, Any], new: dict[str, Any]) -> None:
    """Refuse a write that would drop or change anything already stored."""
    refuse = "refusing to overwrite the memory stored there: "
    if stored["camera"] != new["camera"]:
        raise InputError(where, refuse + "it was taught with another camera calibration")
    if stored.get("front_end") not in (None, new["front_end"]):
        raise InputError(where, refuse + f"its key images were described by front end "
                                         f"{stored['front_end']!r}, these by {new['front_end']!r}")
    for field, key in (("keyframes", "id"), ("paths", "id")):
        kept = {entry[key]: entry for entry in new[field]}
        for entry in stored[field]:
            if kept.get(entry[key]) != entry:
                what = "key image" if field == "keyframes" else "path"
                raise InputError(
                    where, refuse + f"its {what} {entry[key]} is missing or different here"
                )
    for entry in stored["junctions"]:
        if entry not in new["junctions"]:
            raise InputError(
                where,
                refuse + f"its junction {entry['from_id']} -> {entry['to_id']} is missing here",
            )


def _check_fields(path: Path, prefix: str, entry: Any, fields: tuple[str, ...]) -> None:
    if not isinstance(entry, dict):
        raise MemoryFormatError(path, f"{prefix}expected a JSON object, got {_json_type(entry)}")
    for name in fields:
        if name not in entry:
            raise MemoryFormatError(path, f"{prefix}missing field {name!r}")
    unknown = sorted(set(entry) - set(fields))
    if unknown:
        raise MemoryFormatError(path, f"{prefix}unknown field {unknown[0]!r}")


def _array(path: Path, name: str, value: Any) -> list[Any]:
    if not isinstance(value, list):
        raise MemoryFormatError(path, f"{name}: expected a JSON array, got {_json_type(value)}")
    return value


def _record(path: Path, prefix: str, cls: type[Any], entry: Any, fields: tuple[str, ...]) -> Any:
    """``cls(**entry)`` with its fields and its own validation reported as ``path: prefix: ...``."""
    _check_fields(path, f"{prefix}: ", entry, fields)
    try:
        return cls(**entry)
    except MemoryFormatError as e:
        raise MemoryFormatError(path, f"{prefix}: {e.where}: {e.problem}") from None


def _json_type(value: Any) -> str:
    names = {
        dict: "an object",
        list: "an array",
        str: "a string",
        bool: "a boolean",
        int: "an integer",
        float: "a number",
        type(None): "null",
    }
    return names.get(type(value), type(value).__name__)
