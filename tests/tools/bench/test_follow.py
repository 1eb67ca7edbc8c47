"""``vmnav bench follow``: seeded repeats per law, per seed and aggregated (reuses the short
demo's memory as seed 1)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tools.bench.follow import aggregate
from tools.cli import main


def demo_mission(out: Path) -> list[str]:
    """The short demo's world, routes and goal, as options: its memory is reused."""
    goal = json.loads((out / "report.json").read_text())["goal_key_image"]
    return ["--world", str(out.parent / "lab_short.toml"), "--routes", "east_a", "east_b",
            "--goal", str(goal)]


@pytest.mark.slow
def test_a_seed_repeats_on_the_cached_memory_with_people_and_the_light_changed(
        short_demo, tmp_path, capsys) -> None:
    _, out, _ = short_demo
    (tmp_path / "seed1").mkdir()
    shutil.copytree(out / "memory", tmp_path / "seed1" / "memory")
    shutil.copy(out / "teach.json", tmp_path / "seed1" / "teach.json")
    code = main(["bench", "follow", "--seeds", "1", *demo_mission(out), "--laws", "paper+ff",
                 "--out", str(tmp_path), "--people", "2", "--lighting", "scale=0.8,step=0.6@6"])
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert code == 0 and result["benchmark"] == "follow"
    assert "vmnav bench follow: seed 1 paper+ff: reached, lateral RMS" in captured.err
    (row,) = result["seeds"]
    assert row["seed"] == 1 and row["law"] == "paper+ff" and row["reached_goal"]
    assert row["lateral_rms_m"] < 0.05
    assert result["aggregate"]["paper+ff"]["reached_goal"] == 1
    assert result["aggregate"]["paper+ff"]["lateral_rms_m_max"] == row["lateral_rms_m"]
    assert row["scene_change"] == {
        "light_scale": 0.8, "lamps_switched_off": 0, "daylight_hour": None,
        "light_step": {"factor": 0.6, "at_s": 6.0}, "moved_fraction": 0.0, "objects_moved": 0,
        "objects_left_in_place": 0, "pictures_removed": 0, "objects_removed": 0, "doors": {}}


@pytest.mark.parametrize(("args", "message"), [
    (["--laws", "pid"], "unknown law 'pid'"),
    (["--seeds", "0"], "--seeds"),
])
def test_bad_input_is_one_line(tmp_path, capsys, args, message) -> None:
    code = main(["bench", "follow", "--out", str(tmp_path), *args])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and message in err


def test_aggregate_skips_missing_values() -> None:
    rows = [
        {"reached_goal": True, "final_position_error_m": 0.02, "lateral_rms_m": 0.01,
         "lateral_max_m": 0.03, "heading_rms_deg": 0.5, "loop_ms_p50": 8.0, "lost_events": 0},
        {"reached_goal": False, "final_position_error_m": 3.0, "lateral_rms_m": None,
         "lateral_max_m": None, "heading_rms_deg": None, "loop_ms_p50": 10.0, "lost_events": 2},
        {"reached_goal": True, "final_position_error_m": 0.04, "lateral_rms_m": 0.03,
         "lateral_max_m": 0.07, "heading_rms_deg": 0.9, "loop_ms_p50": 9.0, "lost_events": 0},
    ]
    summary = aggregate(rows)
    assert summary["runs"] == 3 and summary["reached_goal"] == 2
    assert summary["final_position_error_m_max"] == 3.0
    assert summary["lateral_rms_m_median"] == 0.02 and summary["lateral_rms_m_max"] == 0.03
    assert summary["lateral_max_m_max"] == 0.07 and summary["loop_ms_p50_median"] == 9.0
    assert summary["lost_events"] == 2
