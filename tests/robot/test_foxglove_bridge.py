"""The robot's live topics over the Foxglove WebSocket protocol: a real server (the SDK's)
on loopback and a client written from the protocol's spec (tools/harness/foxglove_client.py),
fed as the robot's loop feeds it; a port in use; bad config values; the layout shipped for
Foxglove and Lichtblick."""

from __future__ import annotations

import base64
import json
import logging
import math
import socket
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.config import FoxgloveConfig, VmnavConfig
from robot.foxglove_bridge import CHANNELS, FoxgloveBridge, command_of
from robot.mission_run import AppEvent
from robot.vehicle.app_port import VehicleTelemetry
from shared.config import from_mapping
from shared.errors import ConfigError, TransportError
from shared.logs import topics
from shared.mavlink.modes import Mode
from tests.robot.test_field_log import EPOCH_NS, MOUNT, PERIOD_NS, record
from tests.shared.logs.test_schemas import conforms
from tools.harness.foxglove_client import FoxgloveClient, Message, by_topic

LAYOUT = Path(__file__).parents[2] / "docs" / "foxglove" / "vmnav-layout.json"
#: One image per two frames.
CONFIG = FoxgloveConfig(frame_period_ns=2 * PERIOD_NS)


def bridge() -> FoxgloveBridge:
    return FoxgloveBridge("127.0.0.1", 0, CONFIG, MOUNT, unix_offset_ns=EPOCH_NS,
                          where="--foxglove 127.0.0.1:0")


def telemetry(i: int, mode: Mode = Mode.AUTO) -> VehicleTelemetry:
    """After cycle ``i`` of tests.robot.test_field_log.record: its odometry and command."""
    r = record(i, True)
    assert r.follow is not None
    return VehicleTelemetry(mode=mode, odom_pose=r.base.odom_pose,
                            velocity=(r.follow.twist.v_m_s, r.follow.twist.omega_rad_s))


def image(i: int) -> np.ndarray:
    """A (60, 80) frame whose grey level tells ``i``."""
    return np.full((60, 80), 20 * i, np.uint8)


def test_a_client_sees_the_loops_frames_cycles_and_lines_live() -> None:
    with bridge() as live, FoxgloveClient(live.url) as client:
        assert client.server_info["name"] == "vmnav robot"
        client.subscribe(CHANNELS)
        for topic, schema in CHANNELS.items():  # the field log's names
            assert client.channels[topic]["schemaName"] == schema["title"]

        def feed(i: int) -> int:
            """Cycle ``i`` as the loop gives it (the cycle, then its frame); its time."""
            r = record(i, True)
            live.cycle(r, image(i))
            live.offer(r.t_ns, image(i), telemetry(i))
            return r.t_ns

        def state_of(t_ns: int) -> Callable[[list[Message]], bool]:
            return lambda got: any(m.data["stamp_ns"] == t_ns
                                   for m in by_topic(got, topics.SERVO_STATE))

        # Cycle 1 again until the subscription is in force (its servo state comes back),
        # then each cycle once, when the last one's state has come.
        received = client.receive_until(lambda got: state_of(feed(1))(got))
        for i in (2, 3, 4):
            received += client.receive_until(state_of(feed(i)))
        live.event(AppEvent(record(4, True).t_ns, "lost", "no_estimate", "no estimate for 2 s"))
        live.note(record(4, True).t_ns, logging.ERROR, "memory not written")
        received += client.receive_until(lambda got: len(by_topic(got, topics.LOG)) == 2)
    for message in received:  # each decodes under the schema its channel advertised
        conforms(message.data, message.schema, message.topic)
    states = [m.data for m in by_topic(received, topics.SERVO_STATE)]
    # Live: each cycle's own numbers, in order.
    assert [s["lateral_error_m"] for s in states[-3:]] == pytest.approx([0.02, 0.03, 0.04])
    assert states[-1]["key_image_id"] == 6 and states[-1]["mission_state"] == "following"
    servo = by_topic(received, topics.SERVO_STATE)[-1]
    assert servo.log_time_ns == servo.data["stamp_ns"] + EPOCH_NS
    transforms = by_topic(received, topics.TF)[-1].data["transforms"]
    odom = next(t for t in transforms if t["child_frame_id"] == "base_link")
    i = round(odom["translation"]["x"] / 0.1)
    assert odom["translation"]["y"] == pytest.approx(-0.02 * i)
    assert 2 * math.atan2(odom["rotation"]["z"], odom["rotation"]["w"]) == pytest.approx(0.01 * i)
    commands = by_topic(received, topics.CMD_VEL)
    assert {c.data["source"] for c in commands} == {"servo"}
    assert len({c.data["angular_z_rad_s"] for c in commands}) == len(
        {c.data["stamp_ns"] for c in commands}) > 1  # each frame's own
    images = by_topic(received, topics.CAMERA_IMAGE)
    assert 1 <= len(images) <= 2  # at most one per two frames of the four
    jpeg = base64.b64decode(images[-1].data["data"])
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_GRAYSCALE)
    stamp = images[-1].data["timestamp"]
    frame_i = round((stamp["sec"] * 10**9 + stamp["nsec"] - EPOCH_NS - 1_000_000_000)
                    / PERIOD_NS)
    assert decoded.shape == (60, 80) and abs(int(decoded.mean()) - 20 * frame_i) <= 2
    annotations = by_topic(received, topics.CAMERA_ANNOTATIONS)[-1].data
    assert annotations["points"][0]["points"] == [{"x": 10.5, "y": 20.5}, {"x": 30.5, "y": 40.5}]
    assert annotations["texts"][0]["text"] == "key 6: 0 matches"
    lines = [m.data["message"] for m in by_topic(received, topics.LOG)]
    assert lines == ["lost no_estimate: no estimate for 2 s", "memory not written"]
    assert live.dropped == live.errors == 0


def test_outside_a_mission_the_command_is_the_sticks_or_a_stop() -> None:
    assert command_of(5, telemetry(1, Mode.MANUAL), None)["source"] == "teleop"
    stopped = command_of(5, VehicleTelemetry(mode=Mode.HOLD), None)
    assert stopped == {"stamp_ns": 5, "linear_x_m_s": 0.0, "angular_z_rad_s": 0.0,
                       "source": "stop"}
    following = record(1, True)
    assert command_of(following.t_ns, telemetry(1), following)["source"] == "servo"


def test_a_port_in_use_is_one_line() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        with pytest.raises(TransportError) as raised:
            FoxgloveBridge("127.0.0.1", port, CONFIG, MOUNT, unix_offset_ns=0,
                           where=f"--foxglove {port}")
    assert str(raised.value) == (f"--foxglove {port}: cannot listen: Failed to bind port: "
                                 "Address already in use (os error 98)")


def test_bad_config_values_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="frame_period_ns"):
        FoxgloveConfig(frame_period_ns=1)
    with pytest.raises(ConfigError, match=r"foxglove.*jpeg_quality"):
        from_mapping(VmnavConfig, {"foxglove": {"jpeg_quality": 0}}, "robot.toml")
    assert from_mapping(VmnavConfig, {"foxglove": {"address": "9000"}},
                        "robot.toml").foxglove.address == "9000"


def panels(node: str | dict) -> list[str]:
    """The panel ids of a layout's mosaic tree, left to right."""
    return [node] if isinstance(node, str) else panels(node["first"]) + panels(node["second"])


def test_the_shipped_layout_shows_the_bridges_topics_and_fields() -> None:
    """docs/foxglove/vmnav-layout.json (Foxglove's and Lichtblick's layout file): every
    panel placed and configured, every topic and plotted field one the bridge serves, and
    the servo plots the issue asks for."""
    layout = json.loads(LAYOUT.read_text())
    configs = layout["configById"]
    assert sorted(panels(layout["layout"])) == sorted(configs)
    assert {panel.split("!")[0] for panel in configs} == {"Image", "3D", "Plot", "RosOut"}
    (camera,) = [c["imageMode"] for p, c in configs.items() if p.startswith("Image!")]
    assert camera["imageTopic"] == topics.CAMERA_IMAGE
    assert set(camera["annotations"]) == {topics.CAMERA_ANNOTATIONS}
    (scene,) = [c for p, c in configs.items() if p.startswith("3D!")]
    assert {scene["followTf"], *(f.removeprefix("frame:") for f in scene["transforms"])} == {
        topics.FRAME_ODOM, topics.FRAME_BASE, topics.FRAME_CAMERA}
    (log_panel,) = [c for p, c in configs.items() if p.startswith("RosOut!")]
    assert log_panel["topicToRender"] == topics.LOG
    plotted = [path["value"] for p, c in configs.items() if p.startswith("Plot!")
               for path in c["paths"]]
    for value in plotted:
        topic, _, field = value.partition(".")
        assert field in CHANNELS[topic]["properties"], value
    assert {v.partition(".")[2] for v in plotted} >= {
        "matched_points", "lateral_error_m", "angular_error_rad", "err_image_max_px", "v_m_s",
        "omega_rad_s"}
