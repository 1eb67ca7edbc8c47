"""FieldLog (robot/field_log.py): what the robot logs reads back, topic by topic."""

from __future__ import annotations

import base64
import dataclasses
import json
import logging
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from robot.config import ControlConfig, PioneerDriverConfig, VmnavConfig
from robot.control_law import Twist
from robot.field_log import FieldLog, camera_transform
from robot.follower import FollowStep
from robot.logged_missions import mission_start
from robot.mission import MissionState
from robot.mission_run import AppEvent, CycleRecord
from robot.pioneer.client import PioneerClient
from robot.pioneer.status import LinkCounters, LinkState
from robot.replay import generator_from_state
from robot.switching import KeyImageSwitch
from robot.vision.frame_state import FrameState
from robot.vision.image_errors import ImageErrors
from robot.vision.path_state import PathState
from shared.aria.sip import Sip, SipFlags
from shared.config import CameraMountConfig, LogConfig
from shared.interfaces import BaseState
from shared.logs import topics
from shared.logs.messages import image_from_compressed
from shared.logs.reader import LogMessage, log_info, read_messages, read_metadata
from shared.mavlink.dialect import make_codec, mavlink
from tests.shared.logs.test_schemas import conforms

MS = 1_000_000
PERIOD_NS = 66 * MS
#: Unix time at the robot clock's zero (2025-11-14 16:00:00 UTC), ns.
EPOCH_NS = 1_763_136_000_000_000_000
MOUNT = CameraMountConfig(x_m=0.2, y_m=0.01, height_m=0.3)


def record(i: int, following: bool) -> CycleRecord:
    """Cycle ``i``: localizing, or following towards target 1 with a command."""
    t_ns = 1_000 * MS + i * PERIOD_NS
    base = BaseState((0.1 * i, -0.02 * i, 0.01 * i), 0.1 * i, False, False, 12.7, True)
    follow = None if not following else FollowStep(
        t_ns=t_ns, target_index=1, twist=Twist(v_m_s=0.2, omega_rad_s=-0.05 * i), vision=None,
        corners_xy=np.array([[10.0, 20.0], [30.0, 40.0]]), y_m=0.01 * i, theta_rad=-0.002 * i,
        s_m=-0.5 + 0.1 * i, switch=None, lost=None)
    return CycleRecord(t_ns=t_ns, state=MissionState.FOLLOWING if following
                       else MissionState.LOCALIZING, base=base, follow=follow, localization=None,
                       route=(4, 5, 6), compute_ns=0, targets=(4, 6))


def by_topic(files: tuple[Path, ...]) -> dict[str, list[LogMessage]]:
    messages: dict[str, list[LogMessage]] = defaultdict(list)
    for file in files:
        for message in read_messages(file):
            messages[message.topic].append(message)
    return messages


def frame(rng: np.random.Generator) -> np.ndarray:
    return rng.integers(0, 256, (60, 80), dtype=np.uint8)


@pytest.fixture(scope="module")
def logged(tmp_path_factory: pytest.TempPathFactory):
    """Three cycles (localizing, then following target 1 of (4, 6)), an event, a note, a
    SIP and MAVLink packets, one of them garbage: (records, the packet, the final stats)."""
    rng = np.random.default_rng(1)
    folder = tmp_path_factory.mktemp("field")
    vehicle = make_codec(1, 1)
    heartbeat = vehicle.pack(mavlink.MAVLink_heartbeat_message(10, 8, 0, 0, 4, 3))
    records = [record(0, False), record(1, True), record(2, True)]
    with FieldLog(LogConfig(output_dir=str(folder)), "robot", MOUNT,
                  {"robot": "p3at"}, unix_offset_ns=EPOCH_NS) as log:
        for r in records:
            log.cycle(r, frame(rng))
        log.event(AppEvent(records[1].t_ns, "lost", "no_estimate", "no estimate for 2 s"))
        log.note(records[2].t_ns, logging.ERROR, "memory not written")
        log.sip(records[2].t_ns, Sip(flags=SipFlags.MOTORS_ENABLED, battery_v=12.5))
        log.mavlink(records[2].t_ns, "in", heartbeat)
        log.mavlink(records[2].t_ns, "out", b"\xfd\x00garbage")
        log.mavlink(records[2].t_ns + 1, "out", heartbeat)
    return records, heartbeat, log.close()


class TestTopics:
    def test_schemas_and_run_metadata(self, logged) -> None:
        _, _, stats = logged
        (file,) = stats.files
        info = log_info(file)
        assert info.complete
        assert {t.topic: t.schema_name for t in info.topics} == {
            topics.CAMERA_IMAGE: "foxglove.CompressedImage",
            topics.CAMERA_ANNOTATIONS: "foxglove.ImageAnnotations",
            topics.SERVO_STATE: "vmnav.ServoState", topics.BASE_STATE: "vmnav.BaseState",
            topics.CMD_VEL: "vmnav.Command", topics.TF: "foxglove.FrameTransforms",
            topics.LOG: "foxglove.Log", topics.SIP: "vmnav.Sip",
            "/mavlink/in/HEARTBEAT": "mavlink.HEARTBEAT",
            "/mavlink/out/HEARTBEAT": "mavlink.HEARTBEAT", topics.MAVLINK_RAW: "mavlink.Raw"}
        run = read_metadata(file)["run"]
        assert run["robot"] == "p3at" and len(run["series"]) == 32
        # The packet that does not parse is counted, and the writer carried on.
        assert stats.lost == 1 and "not one MAVLink packet" in stats.last_error

    def test_per_cycle_servo_state_base_state_command_and_transforms(self, logged) -> None:
        records, _, stats = logged
        messages = by_topic(stats.files)
        stamps = [r.t_ns for r in records]
        for topic in (topics.CAMERA_IMAGE, topics.CAMERA_ANNOTATIONS, topics.SERVO_STATE,
                      topics.BASE_STATE, topics.TF):
            assert [m.clock_ns for m in messages[topic]] == stamps, topic
            assert [m.log_time_ns for m in messages[topic]] == [EPOCH_NS + t for t in stamps]
        servo = [m.data for m in messages[topics.SERVO_STATE]]
        assert [s["mission_state"] for s in servo] == ["localizing", "following", "following"]
        assert [s["key_image_id"] for s in servo] == [None, 6, 6]  # target 1 of (4, 6)
        assert servo[2]["lateral_error_m"] == records[2].follow.y_m
        assert servo[2]["switch_reason"] is None and servo[0]["target_index"] == -1
        base = messages[topics.BASE_STATE][2].data
        assert ((base["x_m"], base["y_m"], base["yaw_rad"]), base["odom_distance_m"],
                base["battery_v"]) == (records[2].base.odom_pose, 0.2, 12.7)
        commands = [(m.clock_ns, m.data["angular_z_rad_s"]) for m in messages[topics.CMD_VEL]]
        assert [m.data["stamp_ns"] for m in messages[topics.SERVO_STATE]] == stamps
        assert commands == [(r.t_ns, r.follow.twist.omega_rad_s) for r in records[1:]]
        transforms = messages[topics.TF][2].data["transforms"]
        odom, camera = transforms
        assert (odom["parent_frame_id"], odom["child_frame_id"]) == ("odom", "base_link")
        assert odom["translation"]["x"] == records[2].base.odom_pose[0]
        assert camera["translation"] == {"x": 0.2, "y": 0.01, "z": 0.3}
        points = messages[topics.CAMERA_ANNOTATIONS][2].data
        assert points["points"][0]["points"] == [{"x": 10.5, "y": 20.5}, {"x": 30.5, "y": 40.5}]
        assert points["texts"][0]["text"] == "key 6: 0 matches"

    def test_events_notes_sips_and_mavlink(self, logged) -> None:
        _, heartbeat, stats = logged
        messages = by_topic(stats.files)
        lines = [(m.data["level"], m.data["name"], m.data["message"])
                 for m in messages[topics.LOG]]
        assert lines == [(3, "robot.mission_run", "lost no_estimate: no estimate for 2 s"),
                         (4, "robot.runtime", "memory not written")]
        (sip,) = messages[topics.SIP]
        assert sip.data["battery_v"] == 12.5 and sip.data["motors_enabled"]
        raw = [(m.data["direction"], base64.b64decode(m.data["frame"]))
               for m in messages[topics.MAVLINK_RAW]]
        assert raw == [("in", heartbeat), ("out", heartbeat)]
        assert messages["/mavlink/in/HEARTBEAT"][0].data["type"] == 10


def test_every_servo_state_field_is_in_the_schema_the_file_declares(tmp_path: Path) -> None:
    # Localizing, following without an estimate, following with one that completes a key
    # image switch: every field written, null or not, against the schema stored in the file.
    vision = FrameState(PathState(y_m=0.04, theta_rad=-0.01, s_m=-0.3, ok=True,
                                  scale_source="three-view", n_inliers=40, n_points=35),
                        ImageErrors(30.0, 20.0, 40), matches=42)
    switched = record(2, True)
    switch = KeyImageSwitch(t_ns=switched.t_ns, reached_index=0, next_index=1,
                            reason="image_error", err_image_max_px=18.0, s_m=-0.05, final=False)
    switched = dataclasses.replace(switched, follow=dataclasses.replace(
        switched.follow, vision=vision, switch=switch))
    rng = np.random.default_rng(3)
    with FieldLog(LogConfig(output_dir=str(tmp_path)), "robot", MOUNT, {},
                  unix_offset_ns=0) as log:
        for r in (record(0, False), record(1, True), switched):
            log.cycle(r, frame(rng))
    (file,) = log.close().files
    with open(file, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    (schema,) = [json.loads(s.data) for s in summary.schemas.values()
                 if s.name == "vmnav.ServoState"]
    states = [m.data for m in read_messages(file, [topics.SERVO_STATE])]
    assert len(states) == 3
    for state in states:
        assert set(state) <= set(schema["properties"]), set(state) - set(schema["properties"])
        conforms(state, schema)  # and exactly the required keys, of the declared types
    assert (states[2]["lateral_error_raw_m"], states[2]["err_points_px"],
            states[2]["switch_reason"]) == (0.04, 20.0, "image_error")


def test_replay_frames_are_lossless_every_cycle_and_teach_frames_jpeg(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    config = LogConfig(output_dir=str(tmp_path), frame_rate_hz=1.0, replay_frames=True)
    images = [frame(rng) for _ in range(3)]
    with FieldLog(config, "robot", MOUNT, {}, unix_offset_ns=0) as log:
        for i, image in enumerate(images):
            log.cycle(record(i, True), image)
        for i, image in enumerate(images):
            log.teach_frame(10_000 * MS + i * PERIOD_NS, image, (0.1 * i, 0.0, 0.0))
    frames = [image_from_compressed(m.data) for m in read_messages(
        log.close().files[0], [topics.CAMERA_IMAGE])]
    assert [fmt for _, fmt in frames] == ["png"] * 3 + ["jpeg"]  # teach frames at 1 Hz
    assert all(np.array_equal(got, want) for (got, _), want in zip(frames, images, strict=False))


def test_a_mission_start_gives_back_its_config_and_generator(tmp_path: Path) -> None:
    config = dataclasses.replace(
        VmnavConfig(), control=ControlConfig(law="paper+ff", double_pole=0.45),
        log=LogConfig(output_dir="elsewhere", replay_frames=True))
    rng = np.random.default_rng(11)
    rng.random(5)  # a state past the seed
    with FieldLog(LogConfig(output_dir=str(tmp_path)), "robot", MOUNT, {},
                  unix_offset_ns=EPOCH_NS) as log:
        log.mission_started(5 * MS, 7, rng.bit_generator.state, config)
    (file,) = log.close().files
    (message,) = read_messages(file, [topics.MISSION_START])
    start = mission_start(file, message)
    assert (start.t_ns, start.goal_id, start.config) == (5 * MS, 7, config)
    np.testing.assert_array_equal(generator_from_state(start.rng_state).random(8), rng.random(8))


def test_how_the_pioneer_link_ended_is_one_log_line(tmp_path: Path) -> None:
    status = dataclasses.replace(PioneerClient(PioneerDriverConfig()).status,
                                 link=LinkState.CLOSED)
    with FieldLog(LogConfig(output_dir=str(tmp_path)), "robot", MOUNT, {},
                  unix_offset_ns=0) as log:
        log.pioneer_closed(5 * MS, status, LinkCounters())
        log.pioneer_closed(9 * MS, dataclasses.replace(status, last_sip_ns=9 * MS - 12_345_678),
                           LinkCounters(sips=57, link_losses=1, dropped_commands=3,
                                        expired_commands=2))
    lines = [(m.log_time_ns, m.data["name"], m.data["message"])
             for m in read_messages(log.close().files[0], [topics.LOG])]
    assert lines == [
        (5 * MS, "robot.pioneer", "pioneer closed: 0 SIPs; 0 link losses, 0 commands dropped, "
                                  "0 expired"),
        (9 * MS, "robot.pioneer", "pioneer closed: 57 SIPs (the last 12.3 ms before); "
                                  "1 link losses, 3 commands dropped, 2 expired")]


def test_the_camera_transform_of_a_forward_camera() -> None:
    # A forward-looking optical frame (x right, y down, z forward) on base_link (x forward,
    # y left, z up): q_xyzw = (-0.5, 0.5, -0.5, 0.5) (mcap-logging.md sec. 3), up to sign.
    tf = camera_transform(MOUNT)
    assert (tf.parent, tf.child, tf.translation_m) == ("base_link", "camera", (0.2, 0.01, 0.3))
    w, x, y, z = tf.rotation_wxyz
    assert abs(np.dot((x, y, z, w), (-0.5, 0.5, -0.5, 0.5))) == pytest.approx(1.0)
