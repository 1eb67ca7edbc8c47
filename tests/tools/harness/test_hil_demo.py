"""``vmnav demo --hil``: the simulator, the robot process and the ground station as separate
processes on TCP, HTTP and UDP, on a 2.5 m route (about 40 s)."""

from __future__ import annotations

import json

import pytest

from shared.logs.reader import log_info
from tests.tools.short_routes import write_short_routes_world
from tools.cli import main


@pytest.mark.slow
def test_teach_by_teleoperation_then_repeat_over_real_transports(tmp_path, capsys) -> None:
    world = write_short_routes_world(tmp_path)
    out = tmp_path / "hil"
    code = main(["demo", "--hil", "--world", str(world), "--routes", "east_a", "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0, printed
    report = json.loads((out / "report.json").read_text())
    assert report["reached_goal"] and report["route"] == "east_a"
    assert report["final_position_error_m"] < 0.15  # as the lock-step demo test
    assert report["key_images_taught"] >= 5
    assert 1 <= report["key_images_reached"] <= report["key_images_taught"]
    assert report["mean_matches"] > 20
    assert 0 < report["loop_ms_p50"] <= report["loop_ms_p95"] < 1000
    assert report["exit_codes"] == {"robot": 143, "sim": 0}  # SIGTERM; sim serve exits 0
    assert any(n.startswith("path 0 'east_a'") for n in report["notices"])
    assert "hil: taught 'east_a' by teleoperation over MAVLink" in printed
    robot_log = log_info(out / "logs" / "robot-0001.mcap")
    assert robot_log.complete
    topics = {t.topic for t in robot_log.topics}
    assert {"/mission/start", "/servo/state", "/pioneer/sip",
            "/mavlink/in/MANUAL_CONTROL"} <= topics
    assert log_info(out / "logs" / "ground-0001.mcap").complete
    assert list((out / "logs").glob("ground-*.tlog"))
    assert "Traceback" not in (out / "robot.out").read_text()


@pytest.mark.parametrize("args, message", [
    (["--routes", "a,b"], "--routes: --hil teaches one route"),
    (["--routes", "nowhere"], "--route: unknown route 'nowhere'"),
])
def test_bad_input_is_one_line(tmp_path, capsys, args, message) -> None:
    assert main(["demo", "--hil", "--out", str(tmp_path / "hil"), *args]) != 0
    assert message in capsys.readouterr().err


def test_an_existing_memory_is_not_taught_over(tmp_path, capsys) -> None:
    (tmp_path / "hil" / "memory").mkdir(parents=True)
    assert main(["demo", "--hil", "--out", str(tmp_path / "hil")]) != 0
    assert "memory: exists: --hil teaches anew" in capsys.readouterr().err
