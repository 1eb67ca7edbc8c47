"""``vmnav robot --foxglove``: the robot's live topics as Foxglove sees them (bad addresses:
tests/tools/test_bad_inputs.py).

The end-to-end case runs the hardware-in-the-loop rig (tools/harness/hil_rig.py: the
simulator's Pioneer and camera, ``vmnav robot`` as a subprocess, a ground station here)
with ``--foxglove 127.0.0.1:0``; a client written from the protocol's spec
(tests/robot/foxglove_client.py) subscribes to the camera, the servo state, the
transforms and the commands while the robot drives to a key image, and checks that each
decodes under its advertised schema and changes as the robot goes.
"""

from __future__ import annotations

import base64
import re
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.logs import topics
from tests.robot.foxglove_client import FoxgloveClient, Message, by_topic
from tools.harness.hil_rig import open_hil, teach

LIVE = [topics.CAMERA_IMAGE, topics.CAMERA_ANNOTATIONS, topics.SERVO_STATE, topics.TF,
        topics.CMD_VEL]
#: Servo states of distinct frames while following, before the checks.
FOLLOWING_STATES = 8


@pytest.fixture(scope="module")
def taught(tmp_path_factory):
    return teach(tmp_path_factory.mktemp("taught"))


def following(received: list[Message]) -> list[dict]:
    return [m.data for m in by_topic(list(received), topics.SERVO_STATE)
            if m.data["mission_state"] == "following"]


def odom_x(message: Message) -> float:
    (odom,) = [t for t in message.data["transforms"] if t["child_frame_id"] == "base_link"]
    return odom["translation"]["x"]


@pytest.mark.slow
def test_foxglove_sees_the_robot_drive_to_a_key_image(taught, tmp_path: Path) -> None:
    with open_hil(taught, tmp_path, ["--foxglove", "127.0.0.1:0"]) as hil:
        url = re.search(r"live topics for Foxglove on (ws://127\.0\.0\.1:\d+)$",
                        hil.robot.output(), re.M)
        assert url is not None, hil.robot.output()
        received: list[Message] = []
        stop = threading.Event()
        with FoxgloveClient(url.group(1)) as client:
            client.subscribe(LIVE)
            reader = threading.Thread(target=client.receive_until, daemon=True, args=(
                lambda _: stop.is_set(), 120.0, received))
            reader.start()
            try:
                hil.start_goal(taught.keyframe_ids[-1], drive_m=0.2)
                hil.run_until(lambda: len(following(received)) >= FOLLOWING_STATES, 30.0,
                              f"{FOLLOWING_STATES} servo states while following")
            finally:
                stop.set()
                reader.join(10.0)
        output = hil.robot.output()
    assert "Traceback" not in output, output
    states = following(received)
    assert len({s["stamp_ns"] for s in states}) == len(states)  # one per cycle
    assert len({s["lateral_error_m"] for s in states}) > 1  # live: changes as it drives
    assert all(s["key_image_id"] in taught.keyframe_ids and s["matched_points"] > 0
               for s in states)
    transforms = by_topic(received, topics.TF)
    assert odom_x(transforms[-1]) - odom_x(transforms[0]) > 0.05  # east, as taught
    commands = [m.data for m in by_topic(received, topics.CMD_VEL)
                if m.data["source"] == "servo"]
    assert commands and max(c["linear_x_m_s"] for c in commands) > 0
    images = by_topic(received, topics.CAMERA_IMAGE)
    decoded = [cv2.imdecode(np.frombuffer(base64.b64decode(m.data["data"]), np.uint8),
                            cv2.IMREAD_GRAYSCALE) for m in (images[0], images[-1])]
    assert decoded[0].shape == decoded[1].shape == (600, 800)
    assert np.abs(decoded[0].astype(int) - decoded[1]).mean() > 1  # the view changed
    assert any(a.data["points"][0]["points"] for a in
               by_topic(received, topics.CAMERA_ANNOTATIONS))  # the matched corners
