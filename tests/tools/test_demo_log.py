"""The robot log ``vmnav demo`` writes (tools/demo_log.py), read back with shared.logs.reader."""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

from shared.config import CameraMountConfig
from shared.logs import topics
from shared.logs.reader import LogMessage, log_info, read_messages
from shared.logs.schemas import SERVO_STATE
from tools.demo_log import (
    FRAME_BASE_TRUTH,
    FRAME_WORLD,
    TRUTH_TF,
    camera_transform,
)


@pytest.fixture(scope="module")
def demo_log(short_demo) -> Path:
    """The log of the short demo's repeat (the first file: later runs in the same folder
    by other tests add numbered files)."""
    code, out, _ = short_demo
    assert code == 0
    files = sorted((out / "logs").glob("robot-*.mcap"))
    assert files, f"no robot log in {out / 'logs'}"
    return files[0]


@pytest.fixture(scope="module")
def messages(demo_log: Path) -> dict[str, list[LogMessage]]:
    by_topic: dict[str, list[LogMessage]] = defaultdict(list)
    for message in read_messages(demo_log, [topics.CAMERA_ANNOTATIONS, topics.SERVO_STATE,
                                            topics.CMD_VEL, topics.TF, TRUTH_TF, topics.LOG]):
        by_topic[message.topic].append(message)
    return by_topic


def test_the_log_is_complete_with_foxglove_schemas(demo_log: Path) -> None:
    info = log_info(demo_log)
    assert info.complete and info.metadata == ("run",)
    schemas = {t.topic: t.schema_name for t in info.topics}
    assert schemas == {
        topics.CAMERA_IMAGE: "foxglove.CompressedImage",
        topics.CAMERA_ANNOTATIONS: "foxglove.ImageAnnotations",
        topics.TF: "foxglove.FrameTransforms", TRUTH_TF: "foxglove.FrameTransforms",
        topics.LOG: "foxglove.Log", topics.SERVO_STATE: "vmnav.ServoState",
        topics.CMD_VEL: "vmnav.Command"}
    counts = {t.topic: t.message_count for t in info.topics}
    # The demo's 15 frames/s are within the logged frame rate: every cycle has its frame.
    assert counts[topics.CAMERA_IMAGE] == counts[topics.SERVO_STATE] == counts[topics.TF] > 100


def test_one_servo_state_per_cycle_with_the_schema_fields(
        messages: dict[str, list[LogMessage]]) -> None:
    states = messages[topics.SERVO_STATE]
    stamps = np.array([m.log_time_ns for m in states])
    assert [m.data["stamp_ns"] for m in states] == stamps.tolist()
    steps = np.unique(np.diff(stamps))
    assert len(steps) == 1 and 60e6 < steps[0] < 80e6  # no cycle missing or doubled
    for m in states:
        assert set(SERVO_STATE["required"]) <= m.data.keys()
    following = [m.data for m in states if m.data["target_index"] >= 0]
    assert following[-1]["key_image_id"] == 12 and states[-1].data["mission_state"] == "arrived"
    assert all(d["err_image_max_px"] >= d["err_points_px"] for d in following
               if d["err_image_max_px"] is not None)
    commands = messages[topics.CMD_VEL]
    assert len(commands) == len(following)
    assert all(c.data["linear_x_m_s"] == d["v_m_s"] for c, d in zip(commands, following,
                                                                     strict=True))


def test_annotations_share_the_image_timestamps(demo_log: Path,
                                                messages: dict[str, list[LogMessage]]) -> None:
    annotations = messages[topics.CAMERA_ANNOTATIONS]
    image_stamps = [m.log_time_ns for m in read_messages(demo_log, [topics.CAMERA_IMAGE])]
    assert [m.log_time_ns for m in annotations] == image_stamps
    points = annotations[-1].data["points"][0]
    stamp = points["timestamp"]
    assert stamp["sec"] * 10**9 + stamp["nsec"] == image_stamps[-1]
    assert len(points["points"]) > 20
    assert annotations[-1].data["texts"][0]["text"].startswith("key 12: ")


def test_transforms_odometry_camera_and_truth(messages: dict[str, list[LogMessage]]) -> None:
    tf = [{(t["parent_frame_id"], t["child_frame_id"]): t for t in m.data["transforms"]}
          for m in messages[topics.TF]]
    assert all(set(t) == {("odom", "base_link"), ("base_link", "camera")} for t in tf)
    truth = [{(t["parent_frame_id"], t["child_frame_id"]): t for t in m.data["transforms"]}
             for m in messages[TRUTH_TF]]
    assert all(set(t) == {(FRAME_WORLD, "odom"), (FRAME_WORLD, FRAME_BASE_TRUTH)}
               for t in truth)
    # world -> odom is placed so that the first cycle's odometry lands on the truth.
    first_world_odom = _planar(truth[0][FRAME_WORLD, "odom"])
    assert all(_planar(t[FRAME_WORLD, "odom"]) == first_world_odom for t in truth)
    odom, world = _planar(tf[0]["odom", "base_link"]), _planar(truth[0][FRAME_WORLD,
                                                                        FRAME_BASE_TRUTH])
    c, s = math.cos(first_world_odom[2]), math.sin(first_world_odom[2])
    composed = (first_world_odom[0] + c * odom[0] - s * odom[1],
                first_world_odom[1] + s * odom[0] + c * odom[1])
    assert composed == pytest.approx(world[:2], abs=1e-9)
    driven = np.hypot(*np.diff([_planar(t["odom", "base_link"])[:2] for t in tf], axis=0).T)
    assert 4.0 < driven.sum() < 4.7  # the report's 4.34 m, through odometry noise


def test_mission_events_are_log_lines(messages: dict[str, list[LogMessage]]) -> None:
    lines = [m.data["message"] for m in messages[topics.LOG]]
    assert lines[0].startswith("transition start: IDLE -> LOCALIZING")
    assert lines[-1].startswith("transition arrived: FOLLOWING -> ARRIVED")
    assert sum(line.startswith("key_image ") for line in lines) == 11
    assert [m.log_time_ns for m in messages[topics.LOG]] == sorted(
        m.log_time_ns for m in messages[topics.LOG])


def test_the_camera_transform_of_a_forward_camera() -> None:
    # A forward-looking optical frame (x right, y down, z forward) on base_link (x forward,
    # y left, z up): q_xyzw = (-0.5, 0.5, -0.5, 0.5) (mcap-logging.md sec. 3), up to sign.
    tf = camera_transform(CameraMountConfig(x_m=0.2, y_m=0.01, height_m=0.3))
    assert (tf.parent, tf.child, tf.translation_m) == ("base_link", "camera", (0.2, 0.01, 0.3))
    w, x, y, z = tf.rotation_wxyz
    assert abs(np.dot((x, y, z, w), (-0.5, 0.5, -0.5, 0.5))) == pytest.approx(1.0)


def _planar(transform: dict) -> tuple[float, float, float]:
    t, q = transform["translation"], transform["rotation"]
    return t["x"], t["y"], 2 * math.atan2(q["z"], q["w"])
