"""The web app's WebSocket and HTTP routes against a real vehicle endpoint (the tests'
FakeApp behind it), through a real ground station: every request reaches the vehicle as
``vmnav ground`` sends it, and bad input is one line, never a crash."""

from __future__ import annotations

import json
import math
import urllib.error
import urllib.request
from pathlib import Path

import cv2
import numpy as np
import pytest
from websockets.exceptions import InvalidStatus

from ground.web.app import encode
from robot.vehicle.app_port import ServoTelemetry
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory.store import read_memory, thumbnail_path, write_memory
from tests.ground.test_ground_cmd import PhotoApp
from tests.ground.web.conftest import Page, RunningWeb, wait_for
from tests.robot.vehicle.fake_app import FakeApp
from tests.shared.memory.builders import loop_memory


def get(url: str) -> tuple[int, bytes]:
    try:
        with urllib.request.urlopen(url, timeout=60) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


def test_the_page_and_its_modules_are_served_locally(web: RunningWeb) -> None:
    status, html = get(web.url)
    assert status == 200 and b'<script type="module" src="/static/main.js">' in html
    assert b"http" not in html.replace(b"http-equiv", b"")  # no CDN, nothing remote
    for name in ("main.js", "plot.js", "memory.js", "params.js", "teleop.js", "message.js",
                 "camera.js", "graph.js", "logs.js", "style.css"):
        status, body = get(web.url + "static/" + name)
        assert status == 200 and b"https://" not in body and b"http://" not in body, name


def test_updates_show_the_vehicle_with_its_mode_battery_and_link(
        app: FakeApp, page: Page) -> None:
    app.update(mode=Mode.HOLD, odom_pose=(1.5, -0.25, 0.5), velocity=(0.2, 0.1))
    update = page.update_where(lambda u: u["vehicles"] and u["vehicles"][0]["battery_v"]
                               and u["vehicles"][0]["mode"] == "HOLD", "vehicle 1 in HOLD")
    (vehicle,) = update["vehicles"]
    assert vehicle["system_id"] == 1 and vehicle["name"] == "ground rover 1"
    assert vehicle["armed"] and vehicle["battery_v"] == pytest.approx(12.6)
    assert vehicle["failsafes"] == [] and 0.9 <= vehicle["link_received"] <= 1.0
    odometry = page.update_where(lambda u: any(s["kind"] == "odom"
                                               for s in u["samples"].get("1", [])), "odometry")
    sample = next(s for s in odometry["samples"]["1"] if s["kind"] == "odom")
    assert (sample["x"], sample["y"], sample["yaw"]) == pytest.approx((1.5, -0.25, 0.5))
    assert (sample["v"], sample["omega"]) == pytest.approx((0.2, 0.1))


#: Bad requests and the one line each gets (one page sends them all: a page's vehicle is
#: heard after its first heartbeat, up to 1 s).
BAD_REQUESTS = [
    ("not json", "request: not JSON (Expecting value: line 1 column 1 (char 0))"),
    ("[1, 2]", "request: expected a JSON object, got list"),
    ('{"id": 3, "cmd": "fly"}', "cmd: unknown command 'fly' (known: arm, camera, drive, estop, "
                                "goto, hold, memory, mission, mode, param_set, params, route, "
                                "select, teach_start, teach_stop, teleop)"),
    ('{"id": 12, "cmd": "mission", "keys": [1, "2"]}',
     "keys: expected an integer in 0..16777216, got '2'"),
    ('{"id": 4, "cmd": "goto", "key": -1}', "key: expected an integer in 0..16777216, got -1"),
    ('{"id": 5, "cmd": "goto", "key": 1.5}', "key: expected an integer in 0..16777216, got 1.5"),
    ('{"id": 6, "cmd": "mode", "mode": "FLY"}',
     "mode: unknown mode 'FLY' (known: MANUAL, HOLD, AUTO, GUIDED)"),
    ('{"id": 7, "cmd": "drive", "x": 2, "r": 0}', "x: expected a finite number in -1..1, got 2"),
    ('{"id": 8, "cmd": "param_set", "name": "CTL_SPEED", "value": null}',
     "value: expected a finite number, got None"),
    ('{"id": 9, "cmd": "teach_start", "name": "caf\\u00e9"}',
     "name: path name 'café': at most 21 printable ASCII characters"),
    ('{"id": 10, "cmd": "arm", "system": 9}', "system: vehicle 9 not heard (heard: 1)"),
    ('{"id": 11, "cmd": "drive", "x": 0, "r": 0}',
     "drive: this page is not driving: switch teleop on first"),
]


def test_bad_requests_get_one_line_and_the_server_keeps_serving(
        app: FakeApp, page: Page) -> None:
    page.update_where(lambda u: u["vehicles"], "the vehicle heard")
    for count, (text, error) in enumerate(BAD_REQUESTS, start=1):
        page.send(text)
        reply = page.reply()
        assert reply["ok"] is False and reply["error"] == error, text
        assert reply["id"] == json.loads(text).get("id") if text.startswith("{") else True
        assert "\n" not in reply["error"] and "Traceback" not in reply["error"]
        assert page.ask("hold")["ok"], text  # still serving
        assert app.called("set_mode") == [(Mode.HOLD,)] * count, text


def test_binary_and_oversized_messages_are_refused(page: Page) -> None:
    page.ws.send(b"\x00\x01")
    assert page.reply()["error"].startswith("request: not JSON")
    text = json.dumps({"cmd": "arm", "pad": "x" * 5000})
    page.send(text)
    assert page.reply()["error"] == f"request: {len(text)} characters, at most 4096"


def test_a_websocket_from_another_origin_is_refused(web: RunningWeb) -> None:
    with pytest.raises(InvalidStatus):
        Page(web.ws_url, origin="http://evil.example")
    same = Page(web.ws_url, origin=web.url.rstrip("/"))
    same.close()


def test_arm_hold_mode_and_emergency_stop_reach_the_vehicle(app: FakeApp, page: Page) -> None:
    assert page.ask("arm") == {"type": "reply", "id": None, "cmd": "arm", "ok": True,
                               "text": "vehicle 1: armed"}
    assert page.ask("hold")["text"] == "vehicle 1: mode HOLD"
    assert page.ask("mode", mode="MANUAL")["text"] == "vehicle 1: mode MANUAL"
    assert page.ask("mode", mode="AUTO")["error"].startswith(  # the robot's refusal
        "vehicle 1 answered MAV_CMD_DO_SET_MODE with MAV_RESULT_DENIED")  # (and its reason)
    assert page.ask("estop")["text"] == "vehicle 1: emergency stop accepted; holding until armed"
    assert app.called("arm") == [(True, False), (False, True)]
    assert app.called("set_mode") == [(Mode.HOLD,), (Mode.MANUAL,)]
    app.accept = False
    assert page.ask("arm")["error"] == "vehicle 1 answered MAV_CMD_COMPONENT_ARM_DISARM with " \
                                       "MAV_RESULT_DENIED"


def test_goal_by_key_image_and_the_vehicles_refusal(app: FakeApp, page: Page) -> None:
    assert page.ask("goto", key=99)["error"] == (
        "vehicle 1 refused the mission: MAV_MISSION_INVALID_PARAM1 (mission refused: item 0: "
        "no key image 99)")
    assert page.ask("goto", key=3)["text"] == "vehicle 1: going to key image 3"
    assert app.called("start_mission") == [((Goal(3),), 0)]


def test_params_list_and_set(app: FakeApp, page: Page) -> None:
    params = page.ask("params")["params"]
    assert params["CTL_SPEED"] == pytest.approx(0.2) and len(params) >= 10
    reply = page.ask("param_set", name="CTL_SPEED", value=0.35)
    assert reply["value"] == pytest.approx(0.35) and reply["text"] == "vehicle 1: CTL_SPEED = 0.35"
    assert app.configs[-1].control.speed_m_s == pytest.approx(0.35)
    assert page.ask("param_set", name="CTL_SPEED", value=5)["error"].startswith(
        "vehicle 1 kept CTL_SPEED = 0.35, not 5")  # and the reason, when it came in time
    assert page.ask("param_set", name="NO_SUCH", value=1)["error"] == \
        "parameter set NO_SUCH: no such parameter"


def test_teach_start_and_stop(app: FakeApp, page: Page) -> None:
    assert page.ask("teach_start", name="corridor 2")["text"] == \
        "vehicle 1: teaching 'corridor 2'"
    assert page.ask("teach_stop")["text"] == "vehicle 1: teaching stopped"
    assert app.called("teach_start") == [("corridor 2",)] and app.called("teach_stop") == [()]


def manual_controls(app: FakeApp) -> list[tuple[float, float]]:
    return [(x, r) for x, _, _, r, _, _ in app.called("manual_control")]


def test_teleop_sends_the_held_axes_and_stops_when_the_page_goes(
        web: RunningWeb, app: FakeApp) -> None:
    page = Page(web.ws_url)
    assert page.ask("teleop", on=True)["ok"] and app.called("set_mode") == [(Mode.MANUAL,)]
    other = Page(web.ws_url)
    assert other.ask("teleop", on=True)["error"] == "teleop: vehicle 1 is driven from another page"
    other.close()
    page.send(json.dumps({"cmd": "drive", "x": 0.6, "r": -0.3}))
    wait_for(lambda: (0.6, -0.3) in manual_controls(app), "the held axes at the vehicle")
    # The dead-man: the axes are not refreshed, so zeros follow, at 10 Hz.
    wait_for(lambda: manual_controls(app)[-3:] == [(0.0, 0.0)] * 3, "zeros after the lapse")
    page.send(json.dumps({"cmd": "drive", "x": 0.5, "r": 0.0}))
    wait_for(lambda: manual_controls(app)[-1] == (0.5, 0.0), "driving again")
    page.close()  # the page goes away while driving
    later = Page(web.ws_url)
    off = later.update_where(lambda u: u["teleop_owner"] is None, "teleop off")
    later.ask("arm")  # the vehicle handles datagrams in order: the stop came before this
    assert manual_controls(app)[-1] == (0.0, 0.0)
    sent = len(manual_controls(app))
    # No more MANUAL_CONTROL: half a second of the station's time later, still none.
    later.update_where(lambda u: u["t"] >= off["t"] + 0.5, "half a second later")
    later.ask("arm")
    assert len(manual_controls(app)) == sent
    later.close()


def test_memory_index_and_key_image_files_over_ftp(
        vehicle: UdpVehicle, app: FakeApp, web: RunningWeb, page: Page, tmp_path: Path,
        rng: np.random.Generator) -> None:
    assert page.ask("memory")["error"].startswith("FTP ")  # no memory yet on the robot
    write_memory(tmp_path / "memory", loop_memory(rng))
    memory = page.ask("memory", refresh=True)["memory"]
    assert [(p["name"], p["keyframe_ids"]) for p in memory["paths"]] == [
        ("corridor", [0, 1, 2, 3]), ("back", [4, 5, 6])]
    assert memory["keyframes"]["5"]["index"] == 1
    base = web.url + "api/vehicles/1/memory/"
    status, data = get(base + "thumbnails/5.png")
    assert status == 200 and data == thumbnail_path(tmp_path / "memory", 5).read_bytes()
    status, data = get(base + "images/2.png")
    assert status == 200 and data.startswith(b"\x89PNG")
    assert len(data) > 1000 and read_memory(tmp_path / "memory").keyframes[2].image.size
    status, body = get(base + "thumbnails/99.png")
    assert status == 502 and json.loads(body)["error"].startswith(
        "FTP OPEN_FILE_RO /memory/thumbnails/99.png")
    status, body = get(base + "features/1.png")
    assert status == 400 and json.loads(body)["error"] == \
        "kind: 'features' is not one of ['images', 'thumbnails']"
    status, body = get(web.url + "api/vehicles/7/memory/thumbnails/1.png")
    assert status == 400 and json.loads(body)["error"] == \
        "system: vehicle 7 not heard (heard: 1)"
    # Known to the page's memory: a goal outside it is refused before anything is sent.
    assert page.ask("goto", key=42)["error"] == \
        "key: vehicle 1's memory has no key image 42 (7 key images)"
    assert page.ask("mission", keys=[2, 42])["error"] == \
        "key: vehicle 1's memory has no key image 42 (7 key images)"
    assert app.called("start_mission") == []


def test_a_mission_of_several_goals_and_the_route_planned_to_a_key_image(
        app: FakeApp, page: Page, tmp_path: Path, rng: np.random.Generator) -> None:
    write_memory(tmp_path / "memory", loop_memory(rng))
    assert page.ask("route", key=2)["text"] == \
        "key image 2: the start is unknown (vehicle 1 has not said where it is)"
    assert page.ask("mission", keys=[5, 2, 6])["text"] == \
        "vehicle 1: mission of 3 goals: key images 5, 2, 6"
    assert app.called("start_mission") == [((Goal(5), Goal(2), Goal(6)), 0)]
    page.ask("select")  # VISUAL_SERVO_STATUS streams now
    app.update(servo=ServoTelemetry(current_key=5, next_key=6))
    page.update_where(lambda u: any(s.get("current") == 5 for s in u["samples"].get("1", [])),
                      "the vehicle at key image 5")
    reply = page.ask("route", key=2)
    assert (reply["start"], reply["route"]) == (5, [5, 6, 0, 1, 2])  # over the junction 6-0
    assert reply["text"].startswith("key image 2: 5 key images from key image 5 (where the ")
    assert page.ask("route", key=9)["error"] == \
        "key: vehicle 1's memory has no key image 9 (7 key images)"
    assert page.ask("mission", keys=[])["error"] == \
        "keys: expected a list of 1 to 64 key image ids, got []"


def test_numbers_json_lacks_become_null() -> None:
    assert json.loads(encode({"params": {"A": math.nan, "B": 1.5}, "v": [math.inf, 2]})) == \
        {"params": {"A": None, "B": 1.5}, "v": [None, 2]}


def test_a_failed_link_fails_requests_in_one_line_instead_of_hanging(
        web: RunningWeb, page: Page) -> None:
    web.station.link.close()  # the station's socket goes: its loop ends
    reply = page.ask("arm")
    assert reply["error"] == \
        "the ground station's loop has ended (its error is in the server's log)"


def post(url: str, data: bytes, headers: dict[str, str] | None = None) -> tuple[int, dict]:
    request = urllib.request.Request(url, data=data, method="POST", headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=60) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


@pytest.mark.parametrize("app", [PhotoApp()], ids=["photo"])
def test_a_goal_photo_is_uploaded_and_answered_with_the_key_image(
        app: FakeApp, web: RunningWeb, page: Page, tmp_path: Path) -> None:
    photo = cv2.imencode(".png", np.full((60, 80), 128, np.uint8))[1].tobytes()
    wait_for(lambda: 1 in web.station.fleet.vehicles, "vehicle 1 heard")
    status, answer = post(web.url + "api/vehicles/1/goto-photo", photo)
    assert status == 200 and (answer["photo_id"], answer["keyframe_id"]) == (1, 12)
    assert answer["said"].startswith("photo 1.png: key image 12: 40 matches")
    assert [(path.name, data) for path, data in app.called("goto_image")] == [("1.png", photo)]


@pytest.mark.parametrize(("body", "headers", "code", "error"), [
    (b"not an image", {}, 400, "photo: not a PNG or JPEG image"),
    (b"\x89PNG", {"Origin": "http://evil.example"}, 403, "a goal photo from another site"),
])
def test_a_bad_goal_photo_is_refused_in_one_line(
        app: FakeApp, web: RunningWeb, page: Page, body: bytes, headers: dict[str, str],
        code: int, error: str) -> None:
    status, answer = post(web.url + "api/vehicles/1/goto-photo", body, headers)
    assert status == code and answer["error"].startswith(error)
    assert app.called("goto_image") == []
