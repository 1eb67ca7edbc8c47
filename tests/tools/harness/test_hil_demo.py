"""``vmnav demo --hil``: the simulator, the robot process and the ground station as separate
processes on TCP, HTTP and UDP, on a 2.5 m route (about 40 s). It runs with ``--web``: the
operator's steps go through the web app's station loop, and a page (a WebSocket client)
watches it while it runs: the robot heard, its camera, the matches of its frames while it
follows."""

from __future__ import annotations

import json
import re
import threading
import time
import urllib.request
from typing import Any

import pytest

from shared.logs.reader import log_info
from tests.ground.web.conftest import Page
from tests.tools.short_routes import write_short_routes_world
from tools.cli import main

WATCH_URL = re.compile(r"vmnav demo: watch it at (http://127\.0\.0\.1:\d+/) ")


def watch(read: Any, printed: list[str], seen: dict[str, Any]) -> None:
    """A page on the demo while it runs: wait for its URL (``read``: the captured output,
    kept in ``printed``), then note in ``seen`` what the web app showed of it."""
    limit = time.monotonic() + 120
    while not (found := WATCH_URL.search("".join(printed))):
        assert time.monotonic() < limit, "no URL printed"
        printed.append(read().out)
        time.sleep(0.1)
    url = found.group(1)
    page = Page(url.replace("http://", "ws://") + "ws")
    try:
        page.update_where(lambda u: any(v["system_id"] == 1 for v in u["vehicles"]), "robot")
        seen["camera"] = page.ask("camera", system=1)
        page.update_where(lambda u: u["vehicles"][0]["servo_state"] == "following",
                          "the robot following")
        while time.monotonic() < limit + 120 and "matches" not in seen:
            with urllib.request.urlopen(url + "api/vehicles/1/camera-matches.json") as reply:
                if (body := json.loads(reply.read()))["key"] is not None:
                    seen["matches"] = body
            time.sleep(0.2)
    finally:
        page.close()


@pytest.mark.slow
def test_teach_by_teleoperation_then_repeat_over_real_transports(tmp_path, capsys) -> None:
    world = write_short_routes_world(tmp_path)
    out = tmp_path / "hil"
    captured: list[str] = []
    seen: dict[str, Any] = {}
    watcher = threading.Thread(target=watch, args=(capsys.readouterr, captured, seen),
                               daemon=True)
    watcher.start()
    code = main(["demo", "--hil", "--web", "--world", str(world), "--routes", "east_a",
                 "--out", str(out)])
    watcher.join(10)
    printed = "".join(captured) + capsys.readouterr().out
    assert code == 0, printed
    assert seen["camera"]["ok"] and seen["camera"]["camera"]["url"] == "/api/vehicles/1/camera.mjpg"
    matches = seen["matches"]
    assert len(matches["key_xy"]) == len(matches["frame_xy"]) > 0
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


def test_web_needs_hil(tmp_path, capsys) -> None:
    assert main(["demo", "--web", "--out", str(tmp_path / "demo")]) != 0
    assert "--web: needs --hil" in capsys.readouterr().err


def test_an_existing_memory_is_not_taught_over(tmp_path, capsys) -> None:
    (tmp_path / "hil" / "memory").mkdir(parents=True)
    assert main(["demo", "--hil", "--out", str(tmp_path / "hil")]) != 0
    assert "memory: exists: --hil teaches anew" in capsys.readouterr().err
