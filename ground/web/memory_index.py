"""The robot's visual memory as the page's browser needs it: paths and their key images,
from ``/memory/manifest.json`` fetched over MAVLink FTP (pure).

The manifest's format is :mod:`shared.memory.store`'s; this reads only what the browser
shows (paths with their key image ids in order, and each key image's path, index,
distance and teach odometry) and checks just that, so a manifest the robot wrote is
never refused here for a field the page does not use. The camera and the data files stay
on the robot; key images come as files (``thumbnails/<id>.png``, ``images/<id>.png``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from shared.errors import MemoryFormatError
from shared.json_file import parse_json
from shared.memory.store import FORMAT, MANIFEST_NAME

#: Where the robot serves its memory (``robot.vehicle.ftp_memory``).
MEMORY_ROOT = "/memory"
MANIFEST_PATH = f"{MEMORY_ROOT}/{MANIFEST_NAME}"


@dataclass(frozen=True, slots=True)
class MemoryIndex:
    """Paths and key images.

    Attributes:
        paths: ``{"id", "name", "keyframe_ids"}`` per path, in the manifest's order.
        keyframes: key image id -> ``{"path_id", "index", "distance_m", "odom_pose"}``.
    """

    paths: tuple[dict[str, Any], ...]
    keyframes: dict[int, dict[str, Any]]

    def to_json(self) -> dict[str, Any]:
        """For the page (JSON object keys are strings)."""
        return {"paths": list(self.paths),
                "keyframes": {str(k): v for k, v in sorted(self.keyframes.items())}}


def _int(where: str, value: Any) -> int:
    if type(value) is not int or value < 0:
        raise MemoryFormatError(MANIFEST_PATH, f"{where}: expected an integer >= 0, got "
                                               f"{value!r:.40}")
    return value


def _list(where: str, value: Any) -> list[Any]:
    if not isinstance(value, list):
        raise MemoryFormatError(MANIFEST_PATH, f"{where}: expected an array")
    return value


def _object(where: str, value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise MemoryFormatError(MANIFEST_PATH, f"{where}: expected an object")
    return value


def memory_index_from_manifest(data: bytes) -> MemoryIndex:
    """Read the manifest's paths and key images (module docstring).

    Raises:
        MemoryFormatError: not a vmnav memory manifest, or a field the page uses is malformed
            (one line naming it).
    """
    manifest = _object("manifest", parse_json(MANIFEST_PATH, data, MemoryFormatError))
    if manifest.get("format") != FORMAT:
        raise MemoryFormatError(MANIFEST_PATH, f"format: expected {FORMAT!r}, got "
                                               f"{manifest.get('format')!r:.40}")
    paths = []
    for i, entry in enumerate(_list("paths", manifest.get("paths"))):
        entry = _object(f"paths[{i}]", entry)
        name = entry.get("name")
        if not isinstance(name, str):
            raise MemoryFormatError(MANIFEST_PATH, f"paths[{i}].name: expected text")
        ids = [_int(f"paths[{i}].keyframe_ids", k)
               for k in _list(f"paths[{i}].keyframe_ids", entry.get("keyframe_ids"))]
        paths.append({"id": _int(f"paths[{i}].id", entry.get("id")), "name": name,
                      "keyframe_ids": ids})
    keyframes = {}
    for i, entry in enumerate(_list("keyframes", manifest.get("keyframes"))):
        entry = _object(f"keyframes[{i}]", entry)
        pose = entry.get("odom_pose")
        if not (isinstance(pose, list) and len(pose) == 3
                and all(type(v) in (int, float) for v in pose)):
            raise MemoryFormatError(MANIFEST_PATH, f"keyframes[{i}].odom_pose: expected "
                                                   "[x_m, y_m, yaw_rad]")
        distance = entry.get("distance_m")
        if type(distance) not in (int, float):
            raise MemoryFormatError(MANIFEST_PATH, f"keyframes[{i}].distance_m: expected a "
                                                   "number")
        keyframes[_int(f"keyframes[{i}].id", entry.get("id"))] = {
            "path_id": _int(f"keyframes[{i}].path_id", entry.get("path_id")),
            "index": _int(f"keyframes[{i}].index", entry.get("index")),
            "distance_m": float(distance), "odom_pose": [float(v) for v in pose]}
    return MemoryIndex(tuple(paths), keyframes)
