"""``vmnav robot --foxglove``: the robot's live topics as Foxglove sees them (bad addresses:
tests/tools/test_bad_inputs.py).

The case runs the hardware-in-the-loop rig (tools/harness/hil_rig.py: the simulator's
Pioneer and camera, ``vmnav robot`` as a subprocess on the session's taught ``east_a``, a
ground station here) with ``--foxglove 127.0.0.1:0``; a client written from the protocol's spec
(tools/harness/foxglove_client.py) subscribes to the camera, the servo state, the
transforms and the commands while the robot drives to a key image, and checks that each
decodes under its advertised schema and changes as the robot goes.
"""

from __future__ import annotations

import base64
import re
import shutil
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from ground.station import GroundStation
from shared.clock import WallClock
from shared.logs import topics
from shared.memory import read_memory
from tests.shared.logs.test_schemas import conforms
from tools.harness.foxglove_client import FoxgloveClient, Message, by_topic
from tools.harness.hil_rig import Hil, SimSide, start_robot

LIVE = [topics.CAMERA_IMAGE, topics.CAMERA_ANNOTATIONS, topics.SERVO_STATE, topics.TF,
        topics.CMD_VEL]
#: Servo states while following before the checks (about 3 s: two key images passed).
FOLLOWING_STATES = 20


def following(received: list[Message]) -> list[dict]:
    """The servo states of cycles that servoed to a key image."""
    return [m.data for m in by_topic(list(received), topics.SERVO_STATE)
            if m.data["mission_state"] == "following" and m.data["target_index"] >= 0]


def odom_x(message: Message) -> float:
    (odom,) = [t for t in message.data["transforms"] if t["child_frame_id"] == "base_link"]
    return odom["translation"]["x"]


@pytest.mark.slow
def test_foxglove_sees_the_robot_drive_to_a_key_image(east_a, tmp_path: Path) -> None:
    world_file, memory = east_a
    shutil.copytree(memory, tmp_path / "memory")
    (path,) = read_memory(memory).paths.values()
    keys = tuple(path.keyframe_ids)
    received: list[Message] = []
    stop = threading.Event()
    with SimSide(world_file) as sim, \
            GroundStation.open("udpin:127.0.0.1:0", WallClock()) as station:
        hil = Hil(sim, station, start_robot(sim, station, tmp_path, "robot.out",
                                            ["--foxglove", "127.0.0.1:0"]), tmp_path)
        try:
            hil.wait_robot()
            url = re.search(r"live topics for Foxglove on (ws://127\.0\.0\.1:\d+)$",
                            hil.robot.output(), re.M)
            assert url is not None, hil.robot.output()
            with FoxgloveClient(url.group(1)) as client:
                client.subscribe(LIVE)
                reader = threading.Thread(target=client.receive_until, daemon=True, args=(
                    lambda _: stop.is_set(), 120.0, received))
                reader.start()
                try:
                    hil.start_goal(keys[-1], drive_m=0.2)
                    hil.run_until(lambda: len(following(received)) >= FOLLOWING_STATES, 30.0,
                                  f"{FOLLOWING_STATES} servo states while following")
                finally:
                    stop.set()
                    reader.join(10.0)
        finally:
            code = hil.robot.stop()
    output = hil.robot.output()
    assert code == 143 and "Traceback" not in output, output  # SIGTERM, a clean stop
    for message in received:  # each decodes under the schema its channel advertised
        conforms(message.data, message.schema, message.topic)
    states = following(received)
    assert len({s["stamp_ns"] for s in states}) == len(states)  # one per cycle
    assert len({s["lateral_error_m"] for s in states}) > 1  # live: changes as it drives
    assert all(s["key_image_id"] in keys and s["matched_points"] > 0
               for s in states)
    assert len({s["key_image_id"] for s in states}) > 1  # it passed a key image
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
