"""The robot log ``vmnav demo`` writes (tools/harness/demo_log.py: the field log plus the
truth), read back with shared.logs.reader, and replayed."""

from __future__ import annotations

import contextlib
import io
import json
import math
import time
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from robot.mission import MissionState
from robot.mission_run import CycleRecord
from shared.config import CameraMountConfig, LogConfig
from shared.interfaces import BaseState
from shared.logs import topics
from shared.logs.reader import LogMessage, log_info, read_messages
from shared.logs.schemas import SERVO_STATE
from tools.cli import main
from tools.harness.demo_log import FRAME_BASE_TRUTH, FRAME_WORLD, TRUTH_TF, DemoLog

#: Unix time at the simulation clock's zero (2025-11-14 16:00:00 UTC), ns.
EPOCH_NS = 1_763_136_000_000_000_000


@pytest.fixture(scope="module")
def demo_log(short_demo) -> Path:
    """The log of the short demo's repeat."""
    code, out, _ = short_demo
    assert code == 0
    files = sorted((out / "logs").glob("robot-*.mcap"))
    assert files, f"no robot log in {out / 'logs'}"
    return files[0]


@pytest.fixture(scope="module")
def messages(demo_log: Path) -> dict[str, list[LogMessage]]:
    by_topic: dict[str, list[LogMessage]] = defaultdict(list)
    for message in read_messages(demo_log, [topics.CAMERA_ANNOTATIONS, topics.SERVO_STATE,
                                            topics.CMD_VEL, topics.TF, TRUTH_TF, topics.LOG,
                                            topics.MISSION_START]):
        by_topic[message.topic].append(message)
    return by_topic


def test_the_log_is_complete_with_foxglove_schemas(demo_log: Path) -> None:
    info = log_info(demo_log)
    assert info.complete and info.metadata == ("clock", "run")
    # In Unix time, the simulation clock's zero at the wall time the repeat started.
    assert info.start_ns is not None and info.unix_offset_ns is not None
    assert abs(info.start_ns / 1e9 - time.time()) < 3600
    schemas = {t.topic: t.schema_name for t in info.topics}
    assert {
        topics.CAMERA_IMAGE: "foxglove.CompressedImage",
        topics.CAMERA_ANNOTATIONS: "foxglove.ImageAnnotations",
        topics.TF: "foxglove.FrameTransforms", TRUTH_TF: "foxglove.FrameTransforms",
        topics.LOG: "foxglove.Log", topics.SERVO_STATE: "vmnav.ServoState",
        topics.BASE_STATE: "vmnav.BaseState", topics.CMD_VEL: "vmnav.Command",
        topics.MISSION_START: "vmnav.MissionStart"}.items() <= schemas.items()
    counts = {t.topic: t.message_count for t in info.topics}
    # Every cycle's frame is logged (replay_frames), with its state and transforms.
    assert (counts[topics.CAMERA_IMAGE] == counts[topics.SERVO_STATE]
            == counts[topics.BASE_STATE] == counts[TRUTH_TF] > 100)
    assert counts[topics.MISSION_START] == 1


@pytest.mark.slow
def test_the_demo_log_replays_exactly(short_demo, demo_log: Path) -> None:
    _, out, _ = short_demo
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        code = main(["replay", str(demo_log), "--memory", str(out / "memory")])
    assert (code, stderr.getvalue()) == (0, ""), stdout.getvalue()
    assert "identical to the log (tolerance 0)" in stdout.getvalue()


def test_one_servo_state_per_cycle_with_the_schema_fields(
        messages: dict[str, list[LogMessage]], short_demo) -> None:
    states = messages[topics.SERVO_STATE]
    stamps = np.array([m.clock_ns for m in states])
    assert [m.data["stamp_ns"] for m in states] == stamps.tolist()
    steps = np.unique(np.diff(stamps))
    assert len(steps) == 1 and 60e6 < steps[0] < 80e6  # no cycle missing or doubled
    for m in states:
        assert set(SERVO_STATE["required"]) <= m.data.keys()
    following = [m.data for m in states if m.data["target_index"] >= 0]
    report = json.loads((short_demo[1] / "report.json").read_text())
    assert following[-1]["key_image_id"] == report["goal_key_image"]
    assert states[-1].data["mission_state"] == "arrived"
    assert all(d["err_image_max_px"] >= d["err_points_px"] for d in following
               if d["err_image_max_px"] is not None)
    # One switch per key image of the route, from the one it localized at on.
    assert sum(d["switch_reason"] is not None for d in following) == report["key_images_route"]
    commands = messages[topics.CMD_VEL]
    assert len(commands) == len(following)
    assert all(c.data["linear_x_m_s"] == d["v_m_s"] for c, d in zip(commands, following,
                                                                     strict=True))


def test_annotations_share_the_image_timestamps(demo_log: Path,
                                                messages: dict[str, list[LogMessage]],
                                                short_demo) -> None:
    annotations = messages[topics.CAMERA_ANNOTATIONS]
    images = list(read_messages(demo_log, [topics.CAMERA_IMAGE]))
    image_stamps = [m.log_time_ns for m in images]
    assert [m.log_time_ns for m in annotations] == image_stamps
    assert {m.data["format"] for m in images} == {"png"}
    points = annotations[-1].data["points"][0]
    stamp = points["timestamp"]
    assert stamp["sec"] * 10**9 + stamp["nsec"] == image_stamps[-1]
    assert len(points["points"]) > 20
    goal = json.loads((short_demo[1] / "report.json").read_text())["goal_key_image"]
    assert annotations[-1].data["texts"][0]["text"].startswith(f"key {goal}: ")


def test_transforms_odometry_and_camera(messages: dict[str, list[LogMessage]],
                                        short_demo) -> None:
    tf = [{(t["parent_frame_id"], t["child_frame_id"]): t for t in m.data["transforms"]}
          for m in messages[topics.TF]]
    assert all(set(t) == {("odom", "base_link"), ("base_link", "camera")} for t in tf)
    driven = np.hypot(*np.diff([_planar(t["odom", "base_link"])[:2] for t in tf], axis=0).T)
    report = json.loads((short_demo[1] / "report.json").read_text())
    # The true distance the report measured, through odometry noise.
    assert driven.sum() == pytest.approx(report["distance_m"], rel=0.08)


def test_mission_events_are_log_lines(messages: dict[str, list[LogMessage]], short_demo) -> None:
    lines = [m.data["message"] for m in messages[topics.LOG]
             if m.data["name"] == "robot.mission_run"]
    assert lines[0].startswith("transition start: IDLE -> LOCALIZING")
    assert lines[-1].startswith("transition arrived: FOLLOWING -> ARRIVED")
    report = json.loads((short_demo[1] / "report.json").read_text())
    assert sum(line.startswith("key_image ") for line in lines) == report["key_images_route"]
    assert [m.log_time_ns for m in messages[topics.LOG]] == sorted(
        m.log_time_ns for m in messages[topics.LOG])


def test_the_truth_places_the_odometry_in_the_world(tmp_path: Path) -> None:
    truth = [(1.0, 2.0, 0.5), (1.1, 2.05, 0.52), (1.2, 2.1, 0.55)]
    odometry = [(0.3, -0.1, 0.2), (0.4, -0.09, 0.221), (0.5, -0.07, 0.249)]
    with DemoLog(LogConfig(output_dir=str(tmp_path)), CameraMountConfig(),
                 {"seed": "1"}, unix_offset_ns=EPOCH_NS) as log:
        for i, (pose_w, odom) in enumerate(zip(truth, odometry, strict=True)):
            record = CycleRecord(t_ns=i * 66_000_000, state=MissionState.LOCALIZING,
                                 base=BaseState(odom, 0.1 * i, False, False, 12.0, True),
                                 follow=None, localization=None, route=(), compute_ns=0)
            sample = SimpleNamespace(record=record, pose_w=pose_w)
            log.add(None, None, sample)  # type: ignore[arg-type]  # the truth needs no more
    (file,) = log.close().files
    assert file.name == "robot-0001.mcap"
    logged = list(read_messages(file, [TRUTH_TF]))
    assert [m.clock_ns for m in logged] == [0, 66_000_000, 132_000_000]
    assert [m.log_time_ns for m in logged] == [EPOCH_NS, EPOCH_NS + 66_000_000,
                                                EPOCH_NS + 132_000_000]
    frames = [{(t["parent_frame_id"], t["child_frame_id"]): _planar(t)
               for t in m.data["transforms"]} for m in logged]
    np.testing.assert_allclose([f[FRAME_WORLD, FRAME_BASE_TRUTH] for f in frames], truth,
                               atol=1e-12)
    world_odom = frames[0][FRAME_WORLD, "odom"]
    assert all(f[FRAME_WORLD, "odom"] == world_odom for f in frames)  # placed once
    # ... so that the first cycle's odometry lands on the truth.
    (x, y, yaw), odom = world_odom, odometry[0]
    composed = (x + math.cos(yaw) * odom[0] - math.sin(yaw) * odom[1],
                y + math.sin(yaw) * odom[0] + math.cos(yaw) * odom[1], yaw + odom[2])
    assert composed == pytest.approx(truth[0], abs=1e-12)


def _planar(transform: dict) -> tuple[float, float, float]:
    t, q = transform["translation"], transform["rotation"]
    return t["x"], t["y"], 2 * math.atan2(q["z"], q["w"])
