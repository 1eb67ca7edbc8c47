"""The simulator's control endpoint over real HTTP: truth, placement, refusals."""

from __future__ import annotations

import json
import math
import socket
import threading
import time
import urllib.error
import urllib.request

import pytest

from sim.config import SimConfig
from sim.control_server import MAX_OBSTACLES, ControlHook, ControlServer
from sim.simulation import Simulation
from sim.world import load_world


@pytest.fixture(scope="module")
def served():
    """A lab simulation stepping in a thread; its control server's URL (one per module:
    building the lab takes seconds; every test compares with the truth it finds)."""
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


def call(url: str, data: bytes | None = None,
         headers: dict[str, str] | None = None, method: str | None = None) -> tuple[int, dict]:
    """GET (no data) or POST ``data`` as JSON, unless ``headers`` or ``method`` say otherwise."""
    headers = {"Content-Type": "application/json", **(headers or {})}
    method = method or ("GET" if data is None else "POST")
    request = urllib.request.Request(url, data=data, method=method, headers=headers)
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
    (b"not json", "the body is not JSON"),
    (b"{}", "want {\"pose_w\": [x_m, y_m, yaw_rad]}"),
    (json.dumps({"pose_w": ["1", 2, 0]}).encode(), "x_m '1' is not a number"),
    (b'{"pose_w": [1e400, 2, 0]}', "x_m inf is not finite"),
    (json.dumps({"pose_w": [1e308, 2, 0]}).encode(), "outside the world's walls"),
    (json.dumps({"pose_w": [3, -1e308, 0]}).encode(), "outside the world's walls"),
    (json.dumps({"pose_w": [3, 10, 10**400]}).encode(), "not finite"),
    (b"[" * 2000 + b"]" * 2000, "the body is not JSON"),
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


def test_a_1e308_placement_leaves_the_robot_where_it_was(served) -> None:
    url = served
    before = call(url + "/truth")[1]["pose_w"]
    status, _ = call(url + "/place", json.dumps({"pose_w": [1e308, 1e308, 0.0]}).encode())
    assert status == 400
    assert call(url + "/truth")[1]["pose_w"] == pytest.approx(before)


PLACE = json.dumps({"pose_w": [3.0, 10.0, 0.5]}).encode()


@pytest.mark.parametrize("headers, status, message", [
    # What a web page's fetch(..., {method: "POST", mode: "no-cors", body}) sends.
    ({"Content-Type": "text/plain;charset=UTF-8", "Origin": "http://evil.example"}, 403,
     "cross-origin request from 'http://evil.example' refused"),
    ({"Content-Type": "text/plain"}, 415, "must be Content-Type: application/json"),
    ({"Content-Type": "application/x-www-form-urlencoded"}, 415, "application/json"),
    ({"Origin": "null"}, 403, "cross-origin"),
    ({"Host": "rebound.example:80"}, 403, "not this machine's loopback"),
])
def test_requests_from_elsewhere_or_not_json_are_refused(served, headers, status, message
                                                          ) -> None:
    url = served
    before = call(url + "/truth")[1]["pose_w"]
    code, reply = call(url + "/place", PLACE, headers)
    assert code == status and message in reply["error"]
    assert call(url + "/truth")[1]["pose_w"] == pytest.approx(before)


def test_a_same_origin_request_is_served(served) -> None:
    url = served
    origin = url  # http://127.0.0.1:PORT: the server's own
    status, placed = call(url + "/place", PLACE, {"Origin": origin})
    assert status == 200 and placed["pose_w"] == [3.0, 10.0, 0.5]


def test_a_body_too_long_is_refused_unread(served) -> None:
    url = served
    status, reply = call(url + "/place", b" " * 5000 + PLACE)
    assert status == 413 and "at most 4096" in reply["error"]


def test_idle_connections_hold_no_thread_and_a_client_is_still_served(served) -> None:
    url = served
    port = int(url.rpartition(":")[2])
    before = threading.active_count()
    idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(300)]
    try:
        time.sleep(0.5)  # time for the server to accept them all (and, before, to spawn)
        assert threading.active_count() - before <= 2
        status, truth = call(url + "/truth")
        assert status == 200 and len(truth["pose_w"]) == 3
        assert threading.active_count() - before <= 2
    finally:
        for conn in idle:
            conn.close()


BOX = {"pose_w": [6.0, 4.0, 0.3], "size_m": [0.5, 0.4, 0.8]}


def test_a_box_is_placed_listed_and_removed(served) -> None:
    url = served
    status, placed = call(url + "/obstacles", json.dumps(BOX).encode())
    assert status == 200 and isinstance(placed["id"], int) and placed["t_ns"] >= 0
    assert placed["pose_w"] == pytest.approx(BOX["pose_w"]) and placed["sonar"] is True
    assert placed["size_m"] == pytest.approx(BOX["size_m"])
    box_id = placed["id"]
    status, listed = call(url + "/obstacles")
    assert status == 200 and box_id in [b["id"] for b in listed["obstacles"]]
    status, removed = call(url + f"/obstacles/{box_id}", method="DELETE")
    assert status == 200 and removed["id"] == box_id
    assert box_id not in [b["id"] for b in call(url + "/obstacles")[1]["obstacles"]]
    status, reply = call(url + f"/obstacles/{box_id}", method="DELETE")
    assert status == 404 and f"object {box_id}: no object placed" in reply["error"]


def test_a_silent_box_is_placed_as_asked(served) -> None:
    url = served
    status, placed = call(url + "/obstacles", json.dumps({**BOX, "sonar": False}).encode())
    assert status == 200 and placed["sonar"] is False
    assert call(url + f"/obstacles/{placed['id']}", method="DELETE")[0] == 200


@pytest.mark.parametrize("body, message", [
    (b"not json", "the body is not JSON"),
    (b"[]", 'want {"pose_w": [x_m, y_m, yaw_rad], "size_m"'),
    (json.dumps({"pose_w": [6, 4, 0]}).encode(), "got {'pose_w'"),
    (json.dumps({**BOX, "size_m": [0.5, 0.4]}).encode(), "size_m expected 3 numbers, got 2"),
    (json.dumps({**BOX, "size_m": [0.5, -0.4, 0.8]}).encode(),
     "size_m width_m -0.4 is outside [0.05, 5] m"),
    (json.dumps({**BOX, "size_m": [1e9, 0.4, 0.8]}).encode(), "length_m 1e+09 is outside"),
    (json.dumps({**BOX, "size_m": [0.5, 0.4, True]}).encode(), "height_m True is not a number"),
    (b'{"pose_w": [6, 4, 0], "size_m": [0.5, 0.4, NaN]}', "height_m nan is not finite"),
    (b'{"pose_w": [6, 4, 1e400], "size_m": [0.5, 0.4, 0.8]}', "yaw_rad inf is not finite"),
    (json.dumps({**BOX, "pose_w": [-50.0, 4.0, 0.0]}).encode(), "outside the world's walls"),
    (json.dumps({**BOX, "sonar": "no"}).encode(), "sonar 'no' is not true or false"),
    (json.dumps({**BOX, "colour": "red"}).encode(), "unknown field 'colour'"),
])
def test_bad_boxes_are_refused_with_a_reason(served, body, message) -> None:
    url = served
    before = call(url + "/obstacles")[1]
    status, reply = call(url + "/obstacles", body)
    assert status == 400 and message in reply["error"] and "\n" not in reply["error"]
    assert call(url + "/obstacles")[1] == before


def test_a_box_on_the_robot_is_refused(served) -> None:
    url = served
    x, y, _ = call(url + "/truth")[1]["pose_w"]
    status, reply = call(url + "/obstacles", json.dumps({**BOX, "pose_w": [x, y, 0.0]}).encode())
    assert status == 400 and "overlaps the robot" in reply["error"]


def test_no_more_than_the_most_boxes(served) -> None:
    url = served
    ids = []
    for k in range(MAX_OBSTACLES):
        status, placed = call(url + "/obstacles", json.dumps(
            {**BOX, "pose_w": [20.0 + 0.2 * (k % 8), 3.0 + 0.2 * (k // 8), 0.0],
             "size_m": [0.1, 0.1, 0.5]}).encode())
        assert status == 200, placed
        ids.append(placed["id"])
    status, reply = call(url + "/obstacles", json.dumps(BOX).encode())
    assert status == 400 and f"already {MAX_OBSTACLES} boxes placed" in reply["error"]
    for box_id in ids:
        assert call(url + f"/obstacles/{box_id}", method="DELETE")[0] == 200


@pytest.mark.parametrize("path", ["/obstacles/abc", "/obstacles/-1", "/obstacles/1/x",
                                  "/obstacles/" + "9" * 40, "/truth"])
def test_deleting_what_is_not_a_box_is_404(served, path) -> None:
    status, reply = call(served + path, method="DELETE")
    assert status == 404 and reply["error"]


def test_a_cross_origin_delete_is_refused(served) -> None:
    url = served
    status, placed = call(url + "/obstacles", json.dumps(BOX).encode())
    assert status == 200
    status, reply = call(url + f"/obstacles/{placed['id']}", method="DELETE",
                         headers={"Origin": "http://evil.example"})
    assert status == 403 and "cross-origin" in reply["error"]
    assert call(url + f"/obstacles/{placed['id']}", method="DELETE")[0] == 200
