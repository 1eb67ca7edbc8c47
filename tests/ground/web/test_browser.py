"""The page in headless Chromium against ``vmnav ground web``'s server and a real vehicle
endpoint (the tests' FakeApp behind it): fleet, buttons, memory browser, teleop."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robot.vehicle.udp_vehicle import UdpVehicle
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory.store import write_memory
from tests.ground.web.conftest import RunningWeb, console_errors, wait_for
from tests.robot.vehicle.fake_app import FakeApp
from tests.shared.memory.builders import loop_memory


def text_of(driver, element_id: str) -> str:
    return driver.find_element("id", element_id).text


@pytest.mark.slow
def test_fleet_buttons_and_a_goal_clicked_in_the_memory(
        vehicle: UdpVehicle, app: FakeApp, web: RunningWeb, chromium, tmp_path: Path,
        rng: np.random.Generator) -> None:
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

    thumbnails[5].click()
    wait_for(lambda: chromium.find_element("id", "large-caption").text.startswith(
        "key image 5: 2 of 3 on path 'back'"), "key image 5 large")
    chromium.find_element("id", "large-go").click()
    wait_for(lambda: app.called("start_mission") == [((Goal(5),), 0)], "the goal at the vehicle")
    wait_for(lambda: text_of(chromium, "message") == "vehicle 1: going to key image 5",
             "the reply shown")

    # A goal typed that the memory does not hold: one line, nothing sent.
    chromium.find_element("id", "goal-key").send_keys("42")
    chromium.find_element("css selector", "#goal-form button").click()
    wait_for(lambda: "memory has no key image 42" in text_of(chromium, "message"), "the refusal")
    assert chromium.find_element("id", "message").get_attribute("class") == "error"
    assert len(app.called("start_mission")) == 1

    chromium.find_element("id", "estop").click()
    wait_for(lambda: (False, True) in app.called("arm"), "the forced disarm at the vehicle")
    assert console_errors(chromium) == []
