from __future__ import annotations

import numpy as np
import pytest

from shared.memory import VisualMemory, memory_summary, summary_text
from shared.memory.summary import id_ranges
from tests.shared.memory.builders import loop_memory, make_records, small_camera


def test_known_spacing_and_connectivity(rng: np.random.Generator) -> None:
    memory = VisualMemory(small_camera())
    memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 1.0]))
    memory.add_path("stub", make_records(rng, memory.camera, []))
    summary = memory_summary(memory)
    corridor, stub = summary["paths"]
    assert corridor == {
        "id": 0,
        "name": "corridor",
        "keyframe_count": 4,
        "first_id": 0,
        "last_id": 3,
        "length_m": 2.0,
        "spacing_m": {"mean": pytest.approx(2.0 / 3.0), "min": 0.5, "max": 1.0},
        "keyframes_per_m": 1.5,
    }
    assert stub["spacing_m"] is None and stub["keyframes_per_m"] is None
    assert (summary["keyframe_count"], summary["path_count"], summary["length_m"]) == (5, 2, 2.0)
    assert summary["keyframes_per_m"] == 1.5
    assert summary["connectivity"] == {
        "strongly_connected": False,
        "component_count": 5,
        "unreachable_ids": [1, 2, 3, 4],
        "not_reachable_from_main": [4],
        "cannot_reach_main": [1, 2, 3, 4],
    }
    assert summary["junctions"] == []


def test_junctions_name_their_paths(rng: np.random.Generator) -> None:
    summary = memory_summary(loop_memory(rng))
    assert summary["junctions"][1] == {
        "from_id": 6, "to_id": 0, "matches": 75, "from_path_id": 1, "to_path_id": 0
    }
    assert summary["connectivity"]["strongly_connected"]
    assert summary_text(summary).endswith("strongly connected: yes")


def test_empty_memory_text() -> None:
    text = summary_text(memory_summary(VisualMemory(small_camera())))
    assert text.splitlines()[:4] == [
        "0 key images on 0 paths, 0.00 m taught; camera 160x120 px, 185 deg",
        "spacing n/a (no path has two key images)",
        "paths:",
        "  none",
    ]


def test_rotation_in_place_has_no_density(rng: np.random.Generator) -> None:
    memory = VisualMemory(small_camera())
    memory.add_path("spin", make_records(rng, memory.camera, [0.0, 0.0]))
    summary = memory_summary(memory)
    assert summary["keyframes_per_m"] is None
    assert "no distance travelled" in summary_text(summary)


@pytest.mark.parametrize(
    ("ids", "text"),
    [([], "none"), ([4], "4"), ([0, 1, 2, 5, 7, 8], "0-2, 5, 7-8"), ([9, 3, 4], "3-4, 9")],
)
def test_id_ranges(ids: list[int], text: str) -> None:
    assert id_ranges(ids) == text
