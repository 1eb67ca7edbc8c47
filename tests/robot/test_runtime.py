"""RobotRuntime in the simulator, lock-step: teleoperation, teaching over the link, missions,
photo goals, and the requests it refuses.

The robot drives the emulated Pioneer through the real ARIA driver
(:func:`tools.harness.lockstep_pioneer.lockstep_pioneer`) and sees rendered frames; the runtime
is called as the vehicle endpoint calls it (its VehicleApp methods) and as the robot's
loop calls it (``step`` per frame, ``stall``).
"""

from __future__ import annotations

import logging
import math
import shutil
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.config import VmnavConfig
from robot.mission import MissionState
from robot.runtime import RobotRuntime
from robot.vehicle.app_port import JobOutcome
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory import read_memory
from shared.memory.store import thumbnail_path
from shared.pose import Pose2
from sim.config import SimConfig
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import load_world
from tools.bench.hostile_images import bogus_chunk_png
from tools.harness.lockstep_pioneer import lockstep_pioneer

#: Every test here drives the simulator in lock-step on the taught route: seconds each.
pytestmark = pytest.mark.slow

CONFIG = VmnavConfig()


@pytest.fixture
def taught(east_a: tuple[Path, Path]) -> tuple[Path, Path]:
    """(world file, memory folder) with ``east_a`` taught (seed 1; tests/conftest.py)."""
    return east_a


class SimRobot:
    """The runtime on a lock-step simulation, placed at ``pose``."""

    def __init__(self, world_file: Path, memory_dir: Path, pose: Pose2,
                 config: VmnavConfig = CONFIG) -> None:
        self.sim = Simulation(load_world(world_file), SimConfig(world=str(world_file), seed=1))
        self.sim.place_robot(pose)
        self.clock = SimClock(self.sim)
        rng = np.random.default_rng(7)
        self.base, self.pioneer = lockstep_pioneer(self.clock, config.pioneer, rng)
        self.memory_dir = memory_dir
        memory = read_memory(memory_dir)
        self.frames = SimFrameSource(self.sim, memory.camera, self.clock)
        self.runtime = RobotRuntime(memory, memory_dir, config, self.base, self.clock, rng,
                                    lockstep=True)
        self.notices: list[tuple[int, str]] = []

    def run(self, seconds: float, until=lambda t: False) -> None:
        """Step frame by frame for at most ``seconds`` of simulated time, or until
        ``until(telemetry)``; collects the notices."""
        period = self.sim.config.frame_period_ns
        deadline = self.clock.now_ns()
        end = deadline + round(seconds * 1e9)
        while self.clock.now_ns() < end:
            self.runtime.step(*self.frames.read())
            while (notice := self.runtime.next_notice()) is not None:
                self.notices.append(notice)
            if until(self.runtime.telemetry()):
                return
            deadline += period
            self.clock.sleep_until_ns(deadline)

    def drive(self, seconds: float, x: float, r: float = 0.0) -> None:
        """Teleoperate: a MANUAL_CONTROL every frame for ``seconds``."""
        period = self.sim.config.frame_period_ns
        for _ in range(round(seconds * 1e9 / period)):
            self.runtime.manual_control(x, math.nan, math.nan, r, 0, 0)
            self.run(period / 1e9)

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.sim.body.pose_w


@pytest.fixture
def memory_dir(taught, tmp_path) -> Path:
    """A copy of the taught memory the test may change."""
    shutil.copytree(taught[1], tmp_path / "memory")
    return tmp_path / "memory"


#: The start of ``east_a``, facing along it.
EAST_A = Pose2(2.0, 10.0, 0.0)


class TestTeleoperation:
    def test_manual_control_drives_and_the_dead_man_stops(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        assert robot.runtime.telemetry().mode is Mode.HOLD
        robot.runtime.manual_control(1.0, math.nan, math.nan, 0.0, 0, 0)
        robot.run(1.0)
        assert robot.pose[0] == pytest.approx(2.0, abs=0.005)  # HOLD ignores the stick
        assert robot.runtime.set_mode(Mode.MANUAL)
        robot.drive(2.0, x=0.5)
        moved = robot.pose[0] - 2.0
        assert 0.2 < moved < 0.45  # 0.2 m/s after the ramp
        assert robot.runtime.telemetry().velocity == pytest.approx((0.2, 0.0))
        robot.run(2.0)  # no MANUAL_CONTROL: the dead-man stops it within 0.5 s + braking
        stopped = robot.pose[0]
        robot.run(1.0)
        assert robot.pose[0] == pytest.approx(stopped, abs=1e-3)
        assert robot.pose[0] - 2.0 < moved + 0.2
        assert robot.runtime.telemetry().velocity == (0.0, 0.0)

    def test_gcs_lost_in_manual_stops_at_once(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        robot.runtime.set_mode(Mode.MANUAL)
        robot.drive(1.0, x=1.0)
        robot.runtime.manual_control(1.0, math.nan, math.nan, 0.0, 0, 0)
        robot.runtime.gcs_lost("stop")
        robot.run(0.1)
        assert robot.runtime.telemetry().velocity == (0.0, 0.0)


class TestMissions:
    def test_an_auto_mission_reaches_its_goals_in_order_then_holds(
            self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, Pose2(2.0, 10.1, math.radians(5.0)))
        ids = robot.runtime.memory.paths[0].keyframe_ids
        goals = (Goal(ids[len(ids) // 2]), Goal(ids[-1]))
        assert robot.runtime.validate_goals(goals) is None
        assert robot.runtime.start_mission(goals, first_seq=1)
        robot.run(60.0, until=lambda t: t.mode is Mode.HOLD and t.reached_seqs)
        t = robot.runtime.telemetry()
        assert t.mission_state is MissionState.ARRIVED, t.mission_detail
        assert t.reached_seqs == (1, 2) and t.mode is Mode.HOLD and t.goal_key == ids[-1]
        assert robot.pose[0] == pytest.approx(4.5, abs=0.15)

    def test_hold_aborts_the_run_and_auto_again_restarts_it(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        goal = (Goal(robot.runtime.memory.paths[0].keyframe_ids[-1]),)
        robot.runtime.start_mission(goal, 0)
        robot.run(4.0)
        assert robot.runtime.telemetry().mission_state is MissionState.FOLLOWING
        assert robot.runtime.set_mode(Mode.HOLD)
        robot.run(1.0)
        t = robot.runtime.telemetry()
        assert t.mode is Mode.HOLD and t.mission_state is MissionState.ABORTED
        assert "mode HOLD" in t.mission_detail
        held = robot.pose
        robot.run(1.0)
        assert robot.pose[0] == pytest.approx(held[0], abs=1e-3)
        robot.runtime.start_mission(goal, 0)
        robot.run(60.0, until=lambda t: t.mode is Mode.HOLD)
        assert robot.runtime.telemetry().mission_state is MissionState.ARRIVED

    def test_goals_are_checked_against_the_memory(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        refusal = robot.runtime.validate_goals((Goal(0), Goal(999)))
        assert refusal is not None and refusal.result == mavlink.MAV_MISSION_INVALID_PARAM1
        assert "item 1: no key image 999" in refusal.reason

    def test_disarmed_the_robot_refuses_missions_and_does_not_move(
            self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        assert robot.runtime.arm(False, force=False)
        robot.run(0.2)
        assert not robot.runtime.telemetry().armed
        assert not robot.runtime.start_mission((Goal(3),), 0)
        robot.runtime.set_mode(Mode.MANUAL)
        robot.drive(1.0, x=1.0)
        assert robot.pose[0] == pytest.approx(2.0, abs=0.005)


class TestSafety:
    """Issue 17 in lock-step: the emergency stop's hold (the obstacle scenarios are in
    tests/tools/harness/test_safety_scenarios.py)."""

    def test_the_emergency_stop_stops_at_once_and_holds_until_armed(
            self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        goal = robot.runtime.memory.paths[0].keyframe_ids[-1]
        robot.runtime.start_mission((Goal(goal),), 0)
        robot.run(4.0)
        assert robot.runtime.telemetry().mission_state is MissionState.FOLLOWING
        assert robot.runtime.arm(False, force=True)  # on the link thread: no loop step yet
        robot.run(0.5)
        at_rest = robot.pose
        robot.run(2.0)
        assert robot.pose[:2] == pytest.approx(at_rest[:2], abs=2e-3)
        t = robot.runtime.telemetry()
        assert (t.armed, t.mission_state, t.mission_detail) == (
            False, MissionState.ABORTED, "e_stop: emergency stop")
        assert robot.runtime.set_mode(Mode.MANUAL)
        robot.drive(1.0, x=1.0)  # disarmed: the stick does nothing
        assert robot.pose[:2] == pytest.approx(at_rest[:2], abs=2e-3)
        assert robot.runtime.arm(True, force=False)
        robot.drive(1.5, x=1.0)
        assert robot.pose[0] > at_rest[0] + 0.1


class TestBaseLost:
    """A cut ARIA cable mid-route (rule 9), longer than the driver's link timeout."""

    CUT_NS = 10_000_000_000

    def start_and_cut(self, robot: SimRobot) -> None:
        """Start a mission to the path's end, cut the cable while following."""
        goal = robot.runtime.memory.paths[0].keyframe_ids[-1]
        robot.runtime.start_mission((Goal(goal),), 0)
        robot.run(4.0)
        assert robot.runtime.telemetry().mission_state is MissionState.FOLLOWING
        robot.pioneer.cut(self.CUT_NS)
        robot.run(3.0)  # the report timeout, then the Pioneer's 2 s watchdog and braking

    def assert_still(self, robot: SimRobot, seconds: float) -> None:
        held = robot.pose
        robot.run(seconds)
        assert robot.pose[:2] == pytest.approx(held[:2], abs=2e-3)

    def test_continue_pauses_the_mission_and_resumes_it_when_the_base_is_back(
            self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        assert CONFIG.mission.base_lost_action == "continue"  # the default
        self.start_and_cut(robot)
        t = robot.runtime.telemetry()
        assert not t.base_reporting and t.mode is Mode.AUTO
        assert (logging.WARNING, "base not reporting: stopped, mission paused") in robot.notices
        self.assert_still(robot, 4.0)
        robot.run(60.0, until=lambda t: t.mode is Mode.HOLD)
        t = robot.runtime.telemetry()
        assert t.mission_state is MissionState.ARRIVED, t.mission_detail
        assert t.base_reporting
        back = [text for _, text in robot.notices if text.startswith("base reporting again")]
        assert len(back) == 1 and back[0].endswith("mission resumes"), robot.notices
        assert robot.pose[0] == pytest.approx(4.5, abs=0.15)

    def test_hold_ends_the_mission_and_the_robot_stays_put_after_the_base_is_back(
            self, taught, memory_dir) -> None:
        config = replace(CONFIG, mission=replace(CONFIG.mission, base_lost_action="hold"))
        robot = SimRobot(taught[0], memory_dir, EAST_A, config)
        self.start_and_cut(robot)
        t = robot.runtime.telemetry()
        assert t.mode is Mode.HOLD and t.mission_state is MissionState.ABORTED
        assert "the base stopped reporting" in t.mission_detail
        assert (logging.WARNING, "base not reporting: stopped, mission held") in robot.notices
        robot.run(20.0, until=lambda t: t.base_reporting)
        assert robot.runtime.telemetry().base_reporting
        self.assert_still(robot, 3.0)
        assert robot.runtime.telemetry().mode is Mode.HOLD


class TestPhotoGoal:
    def test_a_photo_of_a_key_image_is_found_and_reached_in_guided(
            self, taught, memory_dir, tmp_path) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        memory = robot.runtime.memory
        goal = memory.paths[0].keyframe_ids[-3]
        photo = tmp_path / "1.png"
        cv2.imwrite(str(photo), memory.keyframe(goal).image)
        assert robot.runtime.goto_image(photo)
        robot.run(60.0, until=lambda t: t.mode is Mode.HOLD and t.goal_key is not None)
        outcome = robot.runtime.next_job_outcome()
        assert outcome is not None and outcome == JobOutcome("photo", goal, outcome.text)
        assert outcome.text.startswith(f"photo 1.png: key image {goal}: ")
        assert robot.runtime.next_job_outcome() is None  # once
        t = robot.runtime.telemetry()
        assert t.goal_key == goal and t.mission_state is MissionState.ARRIVED
        assert t.mission_seq is None and t.reached_seqs == ()
        assert any(f"key image {goal}" in text for _, text in robot.notices)

    def test_photos_not_in_the_memory_or_unreadable_are_reported(
            self, taught, memory_dir, tmp_path) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        camera = robot.runtime.memory.camera
        noise = np.random.default_rng(0).integers(0, 256, (camera.height, camera.width),
                                                  dtype=np.uint8)
        cv2.imwrite(str(tmp_path / "1.png"), noise)
        cv2.imwrite(str(tmp_path / "2.png"), noise[:100, :100])
        (tmp_path / "3.jpg").write_bytes(b"not an image")
        (tmp_path / "4.png").write_bytes(bogus_chunk_png(np.random.default_rng(0)))
        for name in ("1.png", "2.png", "3.jpg", "4.png"):
            assert robot.runtime.goto_image(tmp_path / name)
        robot.run(0.5)
        texts = [text for _, text in robot.notices]
        assert any(t.startswith("photo 1.png: not in the memory") for t in texts)
        assert "photo 2.png: 100x100 px, the camera's images are 800x600" in texts
        assert ("photo 3.jpg: not a PNG or JPEG image (the file starts with 6e 6f 74 20 61 6e "
                "20 69)") in texts
        assert any(t.startswith("photo 4.png: corrupt PNG: chunk tEXt at byte 33 declares")
                   for t in texts)
        outcomes = []
        while (outcome := robot.runtime.next_job_outcome()) is not None:
            outcomes.append(outcome)
        assert [(o.job, o.value) for o in outcomes] == [("photo", None)] * 4
        assert [o.text.partition(":")[0] for o in outcomes] == [
            "photo 1.png", "photo 2.png", "photo 3.jpg", "photo 4.png"]
        assert robot.runtime.telemetry().mode is Mode.HOLD


class TestTeaching:
    def test_a_path_taught_by_teleoperation_joins_the_memory(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, Pose2(4.5, 10.0, 0.0))
        assert robot.runtime.teach_start("east_b")
        robot.run(0.1)
        assert robot.runtime.telemetry().teaching
        assert robot.runtime.telemetry().mode is Mode.MANUAL
        assert not robot.runtime.teach_start("again")
        assert not robot.runtime.start_mission((Goal(0),), 0)
        robot.drive(12.0, x=0.5)
        taken = robot.runtime.telemetry().teach_thumbnails  # shown while teaching
        assert robot.runtime.teach_stop()
        robot.run(0.1)
        assert not robot.runtime.telemetry().teaching
        assert robot.runtime.telemetry().teach_thumbnails == ()
        stored = read_memory(memory_dir)
        # Each key image taken had the id it got when stored, and its thumbnail.
        ids = stored.paths[1].keyframe_ids
        assert len(taken) >= 2 and [k for k, _ in taken] == list(ids[:len(taken)])
        assert all(png == thumbnail_path(memory_dir, k).read_bytes() for k, png in taken)
        assert [p.name for p in stored.paths.values()] == ["east_a", "east_b"]
        assert len(stored.junctions) >= 1
        assert robot.runtime.memory.paths.keys() == stored.paths.keys()
        (level, text), = [n for n in robot.notices if n[1].startswith("path 1")]
        assert level == logging.INFO and "'east_b'" in text and "1 junction" in text
        # The new path is usable at once: a goal on it is accepted.
        assert robot.runtime.validate_goals((Goal(stored.paths[1].keyframe_ids[-1]),)) is None

    def test_a_drive_too_short_for_a_path_stores_nothing(self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, EAST_A)
        before = (memory_dir / "manifest.json").read_bytes()
        assert not robot.runtime.teach_stop()
        robot.runtime.teach_start("")
        robot.run(0.1)
        robot.runtime.teach_stop()
        robot.run(0.1)
        assert (memory_dir / "manifest.json").read_bytes() == before
        assert any(level == logging.ERROR and "a path needs 0.20 m: nothing stored" in text
                   for level, text in robot.notices)

    def test_a_manifest_lost_while_teaching_stores_nothing_over_the_files(
            self, taught, memory_dir) -> None:
        robot = SimRobot(taught[0], memory_dir, Pose2(4.5, 10.0, 0.0))
        robot.runtime.teach_start("east_b")
        robot.drive(3.0, x=1.0)
        (memory_dir / "manifest.json").unlink()
        files = sorted(p.name for p in memory_dir.rglob("*"))
        robot.runtime.teach_stop()
        robot.run(0.1)
        assert sorted(p.name for p in memory_dir.rglob("*")) == files
        assert any(level == logging.ERROR and "'east_b' not stored" in text
                   and "manifest.json missing" in text for level, text in robot.notices)


def test_a_camera_stall_stops_the_base_and_frames_resume_the_mission(taught, memory_dir) -> None:
    robot = SimRobot(taught[0], memory_dir, EAST_A)
    goal = (Goal(robot.runtime.memory.paths[0].keyframe_ids[-1]),)
    robot.runtime.start_mission(goal, 0)
    robot.run(5.0)
    robot.runtime.stall(robot.clock.now_ns())
    robot.clock.sleep_until_ns(robot.clock.now_ns() + 1_500_000_000)
    robot.runtime.stall(robot.clock.now_ns())
    assert robot.runtime.telemetry().velocity == (0.0, 0.0)
    assert robot.runtime.telemetry().mode is Mode.AUTO
    robot.run(60.0, until=lambda t: t.mode is Mode.HOLD)
    assert robot.runtime.telemetry().mission_state is MissionState.ARRIVED
    texts = [text for _, text in robot.notices]
    assert texts.count("camera stalled: stopped until frames return") == 1
    assert any(t.startswith("camera back after 1.5 s") for t in texts)


def test_config_from_the_ground_applies_to_teleoperation(taught, memory_dir) -> None:
    robot = SimRobot(taught[0], memory_dir, EAST_A)
    robot.runtime.params_changed(replace(CONFIG, teleop=replace(CONFIG.teleop,
                                                                max_speed_m_s=0.1)))
    robot.runtime.set_mode(Mode.MANUAL)
    robot.drive(1.0, x=1.0)
    assert robot.runtime.telemetry().velocity == pytest.approx((0.1, 0.0))


def test_an_unreachable_leg_is_refused_but_a_goal_behind_a_carried_robot_is_not(
        taught, memory_dir) -> None:
    robot = SimRobot(taught[0], memory_dir, EAST_A)
    ids = robot.runtime.memory.paths[0].keyframe_ids
    refusal = robot.runtime.validate_goals((Goal(ids[-1]), Goal(ids[0])))  # paths run one way
    assert refusal is not None and refusal.result == mavlink.MAV_MISSION_DENIED
    assert f"item 1: no route from key image {ids[-1]} to {ids[0]}" in refusal.reason
    robot.runtime.start_mission((Goal(ids[-1]),), 0)
    robot.run(60.0, until=lambda t: t.mode is Mode.HOLD)
    assert robot.runtime.validate_goals((Goal(ids[2]),)) is None  # it may be carried back
