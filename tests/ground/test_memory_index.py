"""memory_index_from_manifest: the paths and key images of a memory written by the store."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ground.memory_index import memory_index_from_manifest
from shared.errors import MemoryFormatError, UnknownKeyframeError
from shared.memory import VisualMemory
from shared.memory.store import write_memory
from tests.shared.memory.builders import loop_memory, make_records, small_camera


def test_reads_what_the_store_writes(tmp_path: Path, rng: np.random.Generator) -> None:
    write_memory(tmp_path, loop_memory(rng))
    index = memory_index_from_manifest((tmp_path / "manifest.json").read_bytes())
    assert [(p["id"], p["name"], p["keyframe_ids"]) for p in index.paths] == [
        (0, "corridor", [0, 1, 2, 3]), (1, "back", [4, 5, 6])]
    assert index.keyframes[5]["path_id"] == 1 and index.keyframes[5]["index"] == 1
    assert index.keyframes[3]["distance_m"] == pytest.approx(1.5)
    assert json.loads(json.dumps(index.to_json()))["keyframes"]["6"]["index"] == 2


@pytest.mark.parametrize("manifest, problem", [
    (b"{", "/memory/manifest.json: "),
    (b'{"format": "other"}', "format: expected 'vmnav-memory', got 'other'"),
    (b'{"format": "vmnav-memory", "paths": {}}', "paths: expected an array"),
    (b'{"format": "vmnav-memory", "paths": [{"id": 0, "name": "a", "keyframe_ids": [-1]}]}',
     "paths[0].keyframe_ids: expected an integer >= 0, got -1"),
    (b'{"format": "vmnav-memory", "paths": [], "keyframes": [{"id": 0, "path_id": 0, '
     b'"index": 0, "distance_m": 0, "odom_pose": [0, 0]}]}',
     "keyframes[0].odom_pose: expected [x_m, y_m, yaw_rad]"),
    (b'{"format": "vmnav-memory", "paths": [{"id": 0, "name": "a", "keyframe_ids": [3]}], '
     b'"keyframes": []}', "paths[0].keyframe_ids: key image 3 is not in keyframes"),
    (b'{"format": "vmnav-memory", "paths": [], "keyframes": [], "junctions": [{"from_id": 0, '
     b'"to_id": 1}]}', "junctions[0]: joins a key image not in keyframes"),
])
def test_a_malformed_manifest_is_one_line(manifest: bytes, problem: str) -> None:
    with pytest.raises(MemoryFormatError) as raised:
        memory_index_from_manifest(manifest)
    assert problem in str(raised.value) and "\n" not in str(raised.value)


def test_routes_planned_on_the_manifest_are_the_robots(
        tmp_path: Path, rng: np.random.Generator) -> None:
    memory = loop_memory(rng)
    write_memory(tmp_path, memory)
    index = memory_index_from_manifest((tmp_path / "manifest.json").read_bytes())
    assert index.junctions == ({"from_id": 3, "to_id": 4}, {"from_id": 6, "to_id": 0})
    for start in range(7):
        for goal in range(7):
            assert index.plan_route(start, goal) == memory.plan_route(start, goal)
    assert index.plan_route(5, 2) == [5, 6, 0, 1, 2]  # through the junction 6 <-> 0
    with pytest.raises(UnknownKeyframeError, match="no key image with id 9"):
        index.plan_route(0, 9)


def test_a_one_way_path_has_no_route_back(tmp_path: Path, rng: np.random.Generator) -> None:
    memory = VisualMemory(small_camera())
    memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5]))
    write_memory(tmp_path, memory)
    index = memory_index_from_manifest((tmp_path / "manifest.json").read_bytes())
    assert index.plan_route(0, 2) == [0, 1, 2] and index.plan_route(2, 0) == []
