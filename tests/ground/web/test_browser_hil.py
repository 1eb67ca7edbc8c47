"""``vmnav ground web`` as its own process, in headless Chromium, with ``vmnav robot`` driving
the simulator's Pioneer (the HIL rig's parts: ``tools.harness.hil_rig``): the robot appears
in the fleet view with its mode, Hold reaches it, a key image clicked in the memory browser
makes it drive there, and the emergency stop stops it. The robot serves its camera
(``--video``): the page finds it through the MAVLink camera protocol and shows it live,
beside the key image the robot heads for, with the points matched drawn on that key image.

Set ``VMNAV_WEB_SCREENSHOT=docs/img/ground-web.png`` to write the README's picture of the
vehicle view."""

from __future__ import annotations

import os
import re
import resource
import shutil
import time
from pathlib import Path

import pytest

from tests.ground.web.conftest import console_errors, wait_for
from tools.harness.hil_rig import ROBOT_START_S, SimSide, start_robot
from tools.harness.vmnav_process import VmnavProcess

SERVING = re.compile(r"serving (http://\S+) \(MAVLink on udpin:127\.0\.0\.1:0, port (\d+)\)")


def camera_frame(driver) -> str | None:
    """A digest of the live camera image the page shows now (None before its first frame):
    the image drawn on a canvas, read back."""
    return driver.execute_script("""
        const img = document.getElementById('camera-image');
        if (!img.complete || img.naturalWidth === 0) return null;
        const canvas = document.createElement('canvas');
        canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
        const context = canvas.getContext('2d');
        context.drawImage(img, 0, 0);
        const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
        let hash = 0;
        for (let i = 0; i < data.length; i += 7) hash = (hash * 31 + data[i]) >>> 0;
        return `${canvas.width}x${canvas.height}:${hash}`;""")


def cpu_s() -> float:
    """CPU time of this process and its children so far, s."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


@pytest.mark.slow
def test_a_simulated_robot_goes_where_a_key_image_is_clicked(
        east_a: tuple[Path, Path], tmp_path: Path, chromium) -> None:
    started = cpu_s()
    world_file, memory = east_a
    shutil.copytree(memory, tmp_path / "memory")
    web = VmnavProcess(["ground", "--connect", "udpin:127.0.0.1:0", "web",
                        "--http", "127.0.0.1:0"], tmp_path / "web.out", 15.0)
    robot = None
    try:
        url, port = wait_for(lambda: (m := SERVING.search(web.output())) and m.groups(),
                             f"vmnav ground web serving ({web.out})", ROBOT_START_S)
        with SimSide(world_file) as sim:
            robot = start_robot(sim, int(port), tmp_path, "robot.out",
                                ["--video", "http:127.0.0.1:0"])
            chromium.get(url)
            row = wait_for(lambda: chromium.find_elements("css selector", "tr[data-system='1']"),
                           "the robot in the fleet view", ROBOT_START_S)[0]
            assert "ground rover 1" in row.text
            first = wait_for(lambda: camera_frame(chromium), "a camera frame in the page")
            wait_for(lambda: camera_frame(chromium) not in (None, first),
                     "the camera image changing")
            assert "400x300" in chromium.find_element("id", "camera-caption").text
            chromium.find_element("id", "hold").click()
            wait_for(lambda: row.find_elements("xpath", "td[3]")[0].text == "HOLD",
                     "mode HOLD from the robot's HEARTBEAT")

            keys = wait_for(lambda: [int(t.get_attribute("data-key")) for t in
                                     chromium.find_elements("css selector", ".strip img")],
                            "the key images")
            goal = keys[-1]
            chromium.find_element("css selector", f".strip img[data-key='{goal}']").click()
            wait_for(lambda: chromium.find_element("id", "large-caption").text.startswith(
                f"key image {goal}: {len(keys)} of {len(keys)} on path 'east_a'"), "it large")
            chromium.find_element("id", "large-go").click()
            wait_for(lambda: sim.truth.moved_m() > 0.3, "the robot driving to the goal")
            wait_for(lambda: "following" in row.text, "the servo state in the fleet view")
            wait_for(lambda: "matches" in chromium.find_element("id", "servo-summary").text
                     and "of" in chromium.find_element("id", "servo-summary").text,
                     "the servo state in the vehicle view")
            wait_for(lambda: chromium.execute_script(
                "const i = document.getElementById('target-image');"
                "return i.complete && i.naturalWidth > 0;"), "the target key image")
            assert chromium.find_element("id", "target-caption").text.startswith(
                "target: key image ")
            wait_for(lambda: chromium.execute_script(
                "return document.getElementById('target-matches').dataset.points > 0 &&"
                " document.getElementById('target-caption').textContent"
                ".includes(\"points matched with the camera's\");"),
                     "the matched points drawn on the target key image")
            # The points' canvas covers the key image exactly, however wide its caption
            # makes the figure (points once fell beside the image).
            image, canvas = chromium.execute_script(
                "return ['target-image', 'target-matches'].map(id => {"
                " const r = document.getElementById(id).getBoundingClientRect();"
                " return [r.left, r.top, r.width, r.height]; });")
            assert canvas == pytest.approx(image, abs=1.0), (image, canvas)
            if path := os.environ.get("VMNAV_WEB_SCREENSHOT"):
                time.sleep(3)  # a few seconds of plots for the picture (not a synchronisation)
                wait_for(lambda: chromium.execute_script(
                    "return document.getElementById('target-matches').dataset.points > 0;")
                         and chromium.find_element("id", "vehicle").text.split("\n")[0]
                         .endswith("following"), "the robot following, its points drawn")
                vehicle = chromium.find_element("id", "vehicle")
                chromium.execute_script("arguments[0].scrollIntoView();", vehicle)
                vehicle.screenshot(path)

            chromium.find_element("id", "estop").click()
            wait_for(lambda: "emergency stop accepted" in
                     chromium.find_element("id", "message").text, "the e-stop's reply")
            stopped_ns = sim.now_ns
            wait_for(lambda: sim.now_ns > stopped_ns + 2_000_000_000, "2 s of simulation")
            assert sim.truth.still(stopped_ns + 1_000_000_000, sim.now_ns) is None
            wait_for(lambda: "disarmed" in row.text, "disarmed in the fleet view")
            assert console_errors(chromium) == []
    finally:
        if robot is not None:
            robot.stop()
        assert web.stop() in (0, 143), web.output()
    output = web.output()
    assert "Traceback" not in output and "ERROR" not in output, output
    used_s = cpu_s() - started
    print(f"CPU of the test (this process, the robot and the web app; not Chromium): "
          f"{used_s:.1f} s")
    assert used_s < 60, f"{used_s:.1f} s of CPU"
