"""The simulator's control endpoint over real HTTP: truth, placement, refusals."""

from __future__ import annotations

import json
import math
import threading
import urllib.error
import urllib.request

import pytest

from sim.config import SimConfig
from sim.control_server import ControlHook, ControlServer
from sim.simulation import Simulation
from sim.world import load_world


@pytest.fixture
def served():
    """A lab simulation stepping in a thread; its control server's URL."""
    sim = Simulation(load_world("lab"), SimConfig())
    hook = ControlHook(sim)
    sim.add_step_hook(hook)
    stop = threading.Event()

    def loop() -> None:
        while not stop.is_set():
            sim.step()
            stop.wait(0.001)

    thread = threading.Thread(target=loop)
    thread.start()
    with ControlServer(hook) as server:
        yield server.url
    stop.set()
    thread.join()


def call(url: str, data: bytes | None = None) -> tuple[int, dict]:
    request = urllib.request.Request(url, data=data, method="GET" if data is None else "POST")
    try:
        with urllib.request.urlopen(request, timeout=5) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def test_truth_and_placement(served) -> None:
    url = served
    status, truth = call(url + "/truth")
    assert status == 200 and len(truth["pose_w"]) == 3 and truth["t_ns"] >= 0
    status, placed = call(url + "/place", json.dumps({"pose_w": [3.0, 10.0, 0.5]}).encode())
    assert status == 200 and placed["pose_w"] == [3.0, 10.0, 0.5]
    x, y, yaw = call(url + "/truth")[1]["pose_w"]
    assert (x, y) == pytest.approx((3.0, 10.0), abs=1e-6) and yaw == pytest.approx(0.5)


@pytest.mark.parametrize("body, message", [
    (b"not json", "want {\"pose_w\": [x_m, y_m, yaw_rad]}"),
    (json.dumps({"pose_w": [1, 2]}).encode(), "expected 3"),
    (json.dumps({"pose_w": [1, 2, math.nan]}).encode(), "not finite"),
])
def test_bad_placements_are_refused_with_a_reason(served, body, message) -> None:
    url = served
    status, reply = call(url + "/place", body)
    assert status == 400 and message in reply["error"]


def test_a_placement_on_a_wall_is_refused_and_the_robot_stays(served) -> None:
    url = served
    before = call(url + "/truth")[1]["pose_w"]
    wall = load_world("lab").walls[0]
    (x0, y0), (x1, y1) = wall.start, wall.end
    status, reply = call(url + "/place", json.dumps(
        {"pose_w": [(x0 + x1) / 2, (y0 + y1) / 2, 0.0]}).encode())
    assert status == 400 and "overlap" in reply["error"]
    assert call(url + "/truth")[1]["pose_w"] == pytest.approx(before)


def test_unknown_paths_are_404(served) -> None:
    url = served
    assert call(url + "/nothing")[0] == 404
    assert call(url + "/truth", b"{}")[0] == 404
