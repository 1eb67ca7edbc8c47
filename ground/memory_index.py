"""The robot's visual memory as the ground needs it (the web page, ``vmnav ground memory
list``): paths and their key images, from ``/memory/manifest.json`` fetched over MAVLink
FTP (pure).

The manifest's format is :mod:`shared.memory.store`'s; this reads only what the browser
shows (paths with their key image ids in order, each key image's path, index, distance
and teach odometry, and the junctions) and checks just that, so a manifest the robot
wrote is never refused here for a field the ground does not use. That is also all route
planning needs: :meth:`MemoryIndex.plan_route` plans with the robot's own planner
(:class:`shared.memory.graph.RouteGraph`) on the manifest's graph. The camera and the
data files stay on the robot; key images come as files (``thumbnails/<id>.png``,
``images/<id>.png``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

from shared.errors import MemoryFormatError
from shared.json_file import parse_json
from shared.memory.graph import RouteGraph, route_edges
from shared.memory.store import FORMAT, MANIFEST_NAME

#: Where the robot serves its memory (``robot.vehicle.ftp_memory``).
MEMORY_ROOT = "/memory"
MANIFEST_PATH = f"{MEMORY_ROOT}/{MANIFEST_NAME}"


@dataclass(frozen=True)
class MemoryIndex:
    """Paths, key images and junctions.

    Attributes:
        paths: ``{"id", "name", "keyframe_ids"}`` per path, in the manifest's order.
        keyframes: key image id -> ``{"path_id", "index", "distance_m", "odom_pose"}``.
        junctions: ``{"from_id", "to_id"}`` per junction (the two key images are one place).
    """

    paths: tuple[dict[str, Any], ...]
    keyframes: dict[int, dict[str, Any]]
    junctions: tuple[dict[str, int], ...] = ()

    def to_json(self) -> dict[str, Any]:
        """For the page (JSON object keys are strings)."""
        return {"paths": list(self.paths),
                "keyframes": {str(k): v for k, v in sorted(self.keyframes.items())},
                "junctions": list(self.junctions)}

    def plan_route(self, start_id: int, goal_id: int) -> list[int]:
        """The key images the robot passes from ``start_id`` to ``goal_id``, both included
        (:meth:`shared.memory.graph.RouteGraph.plan_route`); ``[]`` if unreachable.

        Raises:
            UnknownKeyframeError: either id is not in the memory.
        """
        return self._graph.plan_route(start_id, goal_id)

    @functools.cached_property
    def _graph(self) -> RouteGraph:
        return RouteGraph(self.keyframes, route_edges(
            (p["keyframe_ids"] for p in self.paths),
            {i: k["distance_m"] for i, k in self.keyframes.items()},
            ((j["from_id"], j["to_id"]) for j in self.junctions)))


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
    for i, entry in enumerate(paths):
        missing = [k for k in entry["keyframe_ids"] if k not in keyframes]
        if missing:
            raise MemoryFormatError(MANIFEST_PATH, f"paths[{i}].keyframe_ids: key image "
                                                   f"{missing[0]} is not in keyframes")
    junctions = []
    for i, entry in enumerate(_list("junctions", manifest.get("junctions", []))):
        entry = _object(f"junctions[{i}]", entry)
        pair = {name: _int(f"junctions[{i}].{name}", entry.get(name))
                for name in ("from_id", "to_id")}
        if not all(k in keyframes for k in pair.values()):
            raise MemoryFormatError(MANIFEST_PATH, f"junctions[{i}]: joins a key image not "
                                                   "in keyframes")
        junctions.append(pair)
    return MemoryIndex(tuple(paths), keyframes, tuple(junctions))
