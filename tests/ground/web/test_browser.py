"""The page in headless Chromium against ``vmnav ground web``'s server and a real vehicle
endpoint (the tests' FakeApp behind it): fleet, buttons, memory browser, teleop."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.vehicle.app_port import ServoTelemetry
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory.store import write_memory
from tests.ground.test_ground_cmd import PhotoApp
from tests.ground.web.conftest import RunningWeb, console_errors, wait_for
from tests.robot.vehicle.fake_app import FakeApp
from tests.shared.memory.builders import loop_memory


def text_of(driver, element_id: str) -> str:
    return driver.find_element("id", element_id).text


@pytest.mark.slow
def test_fleet_buttons_and_a_goal_clicked_in_the_memory(
        vehicle: UdpVehicle, app: FakeApp, web: RunningWeb, chromium, tmp_path: Path,
        rng: np.random.Generator) -> None:
    from selenium.webdriver.common.action_chains import ActionChains

    write_memory(tmp_path / "memory", loop_memory(rng))
    app.update(mode=Mode.HOLD)
    chromium.get(web.url)
    row = wait_for(lambda: chromium.find_elements("css selector", "tr[data-system='1']"),
                   "the vehicle in the fleet view")[0]
    wait_for(lambda: "HOLD" in row.text, "its mode")
    assert "ground rover 1" in row.text and "12.6 V" in row.text
    # The page selected the only vehicle: its view, and its memory's thumbnails.
    thumbnails = wait_for(lambda: chromium.find_elements("css selector", ".strip img"),
                          "the key image thumbnails")
    assert [int(t.get_attribute("data-key")) for t in thumbnails] == list(range(7))
    wait_for(lambda: all(chromium.execute_script("return arguments[0].naturalWidth", t) == 80
                         for t in thumbnails), "the thumbnails loaded")

    chromium.find_element("id", "arm").click()
    wait_for(lambda: app.called("arm") == [(True, False)], "ARM at the vehicle")
    wait_for(lambda: text_of(chromium, "message") == "vehicle 1: armed", "the reply shown")

    app.update(servo=ServoTelemetry(current_key=5, next_key=6))  # where the route starts
    thumbnails[1].click()
    wait_for(lambda: chromium.find_element("id", "large-caption").text.startswith(
        "key image 1: 2 of 4 on path 'corridor'"), "key image 1 large")
    wait_for(lambda: text_of(chromium, "large-route").startswith(
        "route: 5 → 6 → 0 → 1 (key image 1: 4 key images from key image 5"), "its route")
    assert [int(t.get_attribute("data-key")) for t in
            chromium.find_elements("css selector", ".strip img.route")] == [0, 1, 5, 6]
    chromium.find_element("id", "large-add").click()
    # The graph: a key image clicked there is shown large too.
    graph = chromium.find_element("id", "memory-graph")
    x, y, width, height = chromium.execute_script(
        "const [x, y] = window.vmnav.memory.graph.spots.get(5); const c = arguments[0];"
        "return [x, y, c.clientWidth, c.clientHeight];", graph)
    ActionChains(chromium).move_to_element_with_offset(
        graph, round(x - width / 2), round(y - height / 2)).click().perform()
    wait_for(lambda: chromium.find_element("id", "large-caption").text.startswith(
        "key image 5: 2 of 3 on path 'back'"), "key image 5 large")
    wait_for(lambda: text_of(chromium, "large-route").startswith("route: 5 (key image 5: 1 "),
             "at the start already")
    chromium.find_element("id", "large-go").click()
    wait_for(lambda: app.called("start_mission") == [((Goal(5),), 0)], "the goal at the vehicle")
    wait_for(lambda: text_of(chromium, "message") == "vehicle 1: going to key image 5",
             "the reply shown")
    chromium.find_element("id", "large-add").click()
    assert text_of(chromium, "mission-goals") == "1 → 5"
    chromium.find_element("id", "hold").click()  # the robot takes no mission while one runs
    wait_for(lambda: text_of(chromium, "message") == "vehicle 1: mode HOLD", "holding")
    chromium.find_element("id", "mission-start").click()
    wait_for(lambda: app.called("start_mission")[1:] == [((Goal(1), Goal(5)), 0)],
             "the mission of two goals at the vehicle")
    wait_for(lambda: text_of(chromium, "message") ==
             "vehicle 1: mission of 2 goals: key images 1, 5", "the reply shown")

    # A goal typed that the memory does not hold: one line, nothing sent.
    chromium.find_element("id", "goal-key").send_keys("42")
    chromium.find_element("css selector", "#goal-form button").click()
    wait_for(lambda: "memory has no key image 42" in text_of(chromium, "message"), "the refusal")
    assert chromium.find_element("id", "message").get_attribute("class") == "error"
    assert len(app.called("start_mission")) == 2

    chromium.find_element("id", "estop").click()
    wait_for(lambda: (False, True) in app.called("arm"), "the forced disarm at the vehicle")
    assert console_errors(chromium) == []


def manual_controls(app: FakeApp) -> list[tuple[float, float]]:
    return [(x, r) for x, _, _, r, _, _ in app.called("manual_control")]


@pytest.mark.slow
def test_teach_a_path_driving_with_keys_and_a_gamepad(
        vehicle: UdpVehicle, app: FakeApp, web: RunningWeb, chromium, tmp_path: Path,
        rng: np.random.Generator) -> None:
    from selenium.webdriver.common.action_chains import ActionChains

    write_memory(tmp_path / "memory", loop_memory(rng))  # reloaded after teaching stops
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "ground-0001.mcap").write_bytes(bytes(2048))
    chromium.get(web.url)
    wait_for(lambda: chromium.find_elements("css selector", "tr[data-system='1']"), "vehicle 1")
    # The ground logs, to download.
    link = wait_for(lambda: chromium.find_elements("css selector", "#log-rows a"), "the logs")[0]
    assert (link.text, link.get_attribute("href")) == (
        "ground-0001.mcap", web.url + "api/logs/ground-0001.mcap")
    assert "2.0 kB" in chromium.find_element("id", "log-rows").text
    wait_for(lambda: chromium.find_elements("css selector", ".strip img"), "the memory")
    chromium.find_element("id", "teach-name").send_keys("hall")
    chromium.find_element("id", "teach-start").click()
    wait_for(lambda: app.called("teach_start") == [("hall",)], "TEACH_START at the vehicle")
    # The key images taken so far (the robot names the last, served over FTP) show as they
    # come; the memory holds 0..6, so the new path's are 7, 8, ...
    thumbnail = cv2.imencode(".png", np.full((60, 80), 90, np.uint8))[1].tobytes()
    app.update(teaching=True, teach_thumbnails=((7, thumbnail),))
    wait_for(lambda: len(chromium.find_elements("css selector", "#teach-strip img")) == 1,
             "the first key image taken")
    app.update(teach_thumbnails=((7, thumbnail), (8, thumbnail), (9, thumbnail)))
    taken = wait_for(lambda: (lambda imgs: len(imgs) == 3 and imgs)(
        chromium.find_elements("css selector", "#teach-strip img")), "three key images taken")
    assert [int(t.get_attribute("data-key")) for t in taken] == [7, 8, 9]
    wait_for(lambda: all(chromium.execute_script("return arguments[0].naturalWidth", t) == 80
                         for t in taken), "their thumbnails loaded")

    chromium.find_element("id", "teleop").click()
    wait_for(lambda: (Mode.MANUAL,) in app.called("set_mode"), "MANUAL at the vehicle")
    wait_for(lambda: text_of(chromium, "drive-state").startswith("driving"), "driving")
    keys = ActionChains(chromium)
    keys.key_down("w").key_down("d").perform()
    wait_for(lambda: (0.6, 0.6) in manual_controls(app), "forward and right at the vehicle")
    keys.key_up("d").perform()
    wait_for(lambda: manual_controls(app)[-1] == (0.6, 0.0), "forward only")
    keys.key_up("w").perform()  # released: the robot stops
    wait_for(lambda: manual_controls(app)[-1] == (0.0, 0.0), "stopped on release")

    # A gamepad (the Gamepad API, stood in for: headless Chromium has none): the left stick
    # forward and to the right, then back to the centre.
    chromium.execute_script(
        "window.stick = [0.5, -1.0];"
        "navigator.getGamepads = () => [{axes: window.stick, buttons: []}];")
    wait_for(lambda: (1.0, 0.5) in manual_controls(app), "the stick at the vehicle")
    chromium.execute_script("window.stick = [0.05, 0.0];")  # inside the dead zone
    wait_for(lambda: manual_controls(app)[-1] == (0.0, 0.0), "stopped at the centre")

    chromium.execute_script("window.stick = [0.0, -0.8];")
    wait_for(lambda: manual_controls(app)[-1] == (0.8, 0.0), "driving again")
    chromium.get("about:blank")  # the page goes away while the stick is held
    wait_for(lambda: manual_controls(app)[-1] == (0.0, 0.0), "stopped when the page went")

    chromium.get(web.url)
    wait_for(lambda: chromium.find_elements("css selector", "tr[data-system='1']"), "vehicle 1")
    assert not chromium.find_element("id", "teleop").is_selected()
    chromium.find_element("id", "teach-stop").click()
    wait_for(lambda: app.called("teach_stop") == [()], "TEACH_STOP at the vehicle")
    wait_for(lambda: text_of(chromium, "message") == "vehicle 1: teaching stopped", "the reply")
    assert console_errors(chromium) == []


@pytest.mark.slow
@pytest.mark.parametrize("app", [PhotoApp()], ids=["photo"])
def test_a_photo_chosen_in_the_page_is_the_goal(
        vehicle: UdpVehicle, app: FakeApp, web: RunningWeb, chromium, tmp_path: Path) -> None:
    photo = tmp_path / "door.png"
    cv2.imwrite(str(photo), np.full((60, 80), 128, np.uint8))
    chromium.get(web.url)
    wait_for(lambda: chromium.find_elements("css selector", "tr[data-system='1']"),
             "the vehicle in the fleet view")
    chromium.find_element("id", "goal-photo").send_keys(str(photo))
    chromium.find_element("id", "goal-photo-go").click()
    wait_for(lambda: text_of(chromium, "message") ==
             "door.png: found at key image 12; going there", "the key image found")
    assert [(path.name, data) for path, data in app.called("goto_image")] == [
        ("1.png", photo.read_bytes())]
    assert console_errors(chromium) == []
