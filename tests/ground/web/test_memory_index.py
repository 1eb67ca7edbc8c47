"""memory_index_from_manifest: the paths and key images of a memory written by the store."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ground.web.memory_index import memory_index_from_manifest
from shared.errors import MemoryFormatError
from shared.memory.store import write_memory
from tests.shared.memory.builders import loop_memory


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
])
def test_a_malformed_manifest_is_one_line(manifest: bytes, problem: str) -> None:
    with pytest.raises(MemoryFormatError) as raised:
        memory_index_from_manifest(manifest)
    assert problem in str(raised.value) and "\n" not in str(raised.value)
