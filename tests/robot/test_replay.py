"""Replay (robot/replay.py, robot/logged_missions.py, ``vmnav replay``) of a logged lock-step
mission: exact on lossless frames, different after a parameter change, approximate on
JPEG frames; bad input.

The robot follows ``east_a`` (taught in the simulator) to key image 2, then to key image
4, through the real ARIA driver on the emulated Pioneer; every cycle goes to two field
logs, one with lossless frames (rotated every 2 s of log time) and one with JPEG frames.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import itertools
import json
import math
import shutil
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from robot import logged_missions
from robot.config import ControlConfig, VmnavConfig
from robot.field_log import FieldLog
from robot.logged_missions import read_missions
from robot.mission_run import CycleRecord, MissionRun
from robot.replay import LoggedCycle, MissionStart, ReplayBase, differs, replay
from shared.clock import unix_offset_ns
from shared.config import LogConfig
from shared.errors import InputError
from shared.interfaces import BaseState, MobileBase
from shared.logs import topics
from shared.logs.reader import LogMessage
from shared.logs.series import log_series
from shared.memory import KeyframeRecord, VisualMemory, read_memory, write_memory
from shared.pose import Pose2
from sim.config import SimConfig
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import load_world
from tests.robot.config.test_config import old_layout
from tools.cli import main
from tools.harness.lockstep_pioneer import lockstep_pioneer

CONFIG = VmnavConfig()
GOALS = (2, 4)


@dataclass(frozen=True)
class Logged:
    memory: Path
    lossless: tuple[Path, ...]
    jpeg: tuple[Path, ...]
    records: tuple[CycleRecord, ...]


class RememberingFrames:
    """The simulator's camera, remembering the last frame (the one the cycle consumed)."""

    def __init__(self, frames: SimFrameSource) -> None:
        self._frames = frames
        self.last: np.ndarray | None = None

    def read(self):
        frame = self._frames.read()
        self.last = None if frame is None else frame[1]
        return frame


@pytest.fixture(scope="module")
def logged(tmp_path_factory: pytest.TempPathFactory, east_a: tuple[Path, Path]) -> Logged:
    """Two missions on ``east_a`` (tests/conftest.py; read only), logged losslessly and as
    JPEG."""
    folder = tmp_path_factory.mktemp("replay")
    world_file, memory_dir = east_a
    world = load_world(world_file)
    sim_config = SimConfig(world=str(world_file), seed=1, camera_mount=CONFIG.camera.mount)
    memory = read_memory(memory_dir)
    camera = memory.camera

    sim = Simulation(world, sim_config)
    sim.place_robot(Pose2(2.05, 10.05, math.radians(3.0)))
    clock = SimClock(sim)
    base, _ = lockstep_pioneer(clock, CONFIG.pioneer, np.random.default_rng(7))
    frames = RememberingFrames(SimFrameSource(sim, camera, clock))
    # The PNG log in Unix time as the entry points write it, the JPEG one with offset 0 (as
    # logs written before the offset was recorded): replay reads the clock back from both.
    logs = [FieldLog(LogConfig(output_dir=str(folder / "png"), replay_frames=True,
                               rotate_period_ns=1_000_000_000), "robot", CONFIG.camera.mount, {},
                     unix_offset_ns=unix_offset_ns(clock)),
            FieldLog(LogConfig(output_dir=str(folder / "jpeg")), "robot", CONFIG.camera.mount, {},
                     unix_offset_ns=0)]
    rng = np.random.default_rng(3)
    records: list[CycleRecord] = []
    for goal in GOALS:
        run = MissionRun(memory, CONFIG, base, rng)
        for log in logs:
            log.mission_started(clock.now_ns(), goal, rng.bit_generator.state, CONFIG)

        def observe(record: CycleRecord, run: MissionRun = run) -> None:
            records.append(record)
            for log in logs:
                log.cycle(record, frames.last)

        result = run.run(goal, frames, clock, sim_config.frame_period_ns, 30 * 10**9, observe)
        assert result.reached_goal
    lossless, jpeg = (log.close() for log in logs)
    assert not (lossless.dropped or jpeg.dropped)
    return Logged(memory_dir, lossless.files, jpeg.files, tuple(records))


def run_cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["replay", *argv])
    return code, out.getvalue(), err.getvalue()


@pytest.mark.slow
class TestReplay:
    def test_a_lossless_log_replays_exactly(self, logged: Logged) -> None:
        assert len(logged.lossless) > 2  # a rotated series, given by its first file
        code, out, err = run_cli(str(logged.lossless[0]), "--memory", str(logged.memory),
                                 "--json")
        assert (code, err) == (0, "")
        report = json.loads(out)
        assert report["files"] == [str(f) for f in logged.lossless]
        assert report["identical"] and report["exact"]
        assert (report["missions"], report["cycles"]) == (2, len(logged.records))
        assert report["skipped"] == report["fed_only"] == report["approximate"] == 0
        assert all(f == {"mismatches": 0, "max_abs_diff": 0.0}
                   for f in report["fields"].values())
        assert report["first_divergence"] is None

    def test_a_log_written_before_the_mount_moved_replays_exactly(
            self, logged: Logged, monkeypatch: pytest.MonkeyPatch) -> None:
        # Its mission starts hold the config as the code before the move stored it: the
        # simulator's tables inside, the camera mount in sim.camera.
        old = old_layout()
        assert "sim" in old and "mount" not in old["camera"]
        # The layout is under test, not the values: this log's missions ran with today's
        # three-view tolerances (tightened since the old layout was stored).
        old["path_state"] = dataclasses.asdict(VmnavConfig().path_state)
        real_read = logged_missions.read_messages

        def read_old_layout(file: Path, wanted: Sequence[str]) -> Iterator[LogMessage]:
            for message in real_read(file, wanted):
                if message.topic == topics.MISSION_START:
                    message = dataclasses.replace(message, data={**message.data, "config": old})
                yield message

        monkeypatch.setattr(logged_missions, "read_messages", read_old_layout)
        code, out, err = run_cli(str(logged.lossless[0]), "--memory", str(logged.memory),
                                 "--json")
        assert (code, err) == (0, "")
        report = json.loads(out)
        assert report["identical"] and report["exact"]
        assert (report["missions"], report["cycles"]) == (2, len(logged.records))

    def test_the_log_holds_what_the_mission_did(self, logged: Logged) -> None:
        items = list(itertools.islice(read_missions(log_series(logged.lossless[:1])), 40))
        assert isinstance(items[0], MissionStart) and items[0].goal_id == GOALS[0]
        cycles = [i for i in items if isinstance(i, LoggedCycle)]
        for cycle, record in zip(cycles, logged.records, strict=False):
            assert (cycle.t_ns, cycle.base, cycle.lossless) == (record.t_ns, record.base, True)
            assert cycle.logged is not None
            assert cycle.logged["mission_state"] == record.state.value
            follow = record.follow
            assert cycle.logged["lateral_error_m"] == (None if follow is None else follow.y_m)

    def test_a_changed_gain_shows_as_a_difference(self, logged: Logged) -> None:
        config = dataclasses.replace(CONFIG, control=dataclasses.replace(CONFIG.control,
                                                                         double_pole=0.6))
        items = itertools.islice(read_missions(log_series(logged.lossless[:1])), 40)
        report = replay(items, read_memory(logged.memory), config=config)
        assert not report.identical and report.exact
        first = report.first
        assert first is not None and first.mission == 0
        assert first.field == "cmd_angular_z_rad_s"  # the law's output moves first
        assert report.fields["cmd_angular_z_rad_s"].max_abs_diff > 1e-3

    def test_a_jpeg_log_replays_approximately(self, logged: Logged) -> None:
        code, out, err = run_cli(str(logged.jpeg[0]), "--memory", str(logged.memory))
        assert code == 1
        assert err.startswith("vmnav replay: warning: ") and "only approximate" in err
        assert f"2 missions, {len(logged.records)} cycles compared" in out
        assert "differs from the log (tolerance 0): first at " in out


class TestBadInput:
    def check(self, code: int, out: str, err: str, message: str) -> None:
        assert (code, out) == (2, "")
        assert err.startswith("vmnav replay: error: ") and err.count("\n") == 1
        assert message in err

    @pytest.mark.slow
    def test_a_log_without_missions(self, logged: Logged, tmp_path: Path) -> None:
        with FieldLog(LogConfig(output_dir=str(tmp_path)), "teach", CONFIG.camera.mount,
                      {}, unix_offset_ns=0) as log:
            log.teach_frame(0, np.zeros((600, 800), np.uint8), (0.0, 0.0, 0.0))
        self.check(*run_cli(str(tmp_path / "teach-0001.mcap"), "--memory", str(logged.memory)),
                   "teach-0001.mcap: no mission start (no messages on /mission/start)")

    @pytest.mark.slow
    def test_a_memory_without_the_goal(self, logged: Logged, tmp_path: Path) -> None:
        memory = read_memory(logged.memory)
        smaller = VisualMemory(memory.camera)
        smaller.add_path("start", [KeyframeRecord(k.t_ns, k.odom_pose, k.distance_m, k.image,
                                                  k.pixels_xy, k.patches, k.tracked_from_previous)
                                   for k in (memory.keyframes[0], memory.keyframes[1])])
        write_memory(tmp_path / "memory", smaller)
        self.check(*run_cli(str(logged.lossless[0]), "--memory", str(tmp_path / "memory")),
                   f"{tmp_path / 'memory'}: has no key image 2, the goal of the mission")

    @pytest.mark.slow
    def test_a_missing_memory(self, logged: Logged, tmp_path: Path) -> None:
        self.check(*run_cli(str(logged.lossless[0]), "--memory", str(tmp_path / "none")),
                   str(tmp_path / "none"))

    @pytest.mark.slow
    def test_a_truncated_file(self, logged: Logged, tmp_path: Path) -> None:
        cut = tmp_path / "robot-0001.mcap"
        data = logged.lossless[0].read_bytes()
        cut.write_bytes(data[: len(data) // 2])
        self.check(*run_cli(str(cut), "--memory", str(logged.memory)),
                   f"`vmnav log recover {cut}`")

    @pytest.mark.slow
    def test_not_an_mcap_file(self, logged: Logged, tmp_path: Path) -> None:
        bad = tmp_path / "robot.mcap"
        bad.write_text("not a log")
        self.check(*run_cli(str(bad), "--memory", str(logged.memory)), "not an MCAP file")

    @pytest.mark.slow
    def test_a_gap_in_the_series(self, logged: Logged, tmp_path: Path) -> None:
        for file in logged.lossless[:3]:
            shutil.copy(file, tmp_path)
        (tmp_path / logged.lossless[1].name).unlink()
        self.check(*run_cli(*(str(tmp_path / f.name) for f in (logged.lossless[0],
                                                              logged.lossless[2])),
                            "--memory", str(logged.memory)),
                   f"{logged.lossless[1].name}: missing from the series")


class ConstantBase:
    """A base at rest (for the core's bookkeeping checks)."""

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        raise AssertionError("not used")

    def stop(self) -> None:
        raise AssertionError("not used")

    def state(self) -> BaseState:
        return BaseState((0.0, 0.0, 0.0), 0.0, False, False, 12.0, True)


class TestCore:
    def test_the_replay_base_reports_logged_states_and_records_commands(self) -> None:
        base = ReplayBase()
        assert isinstance(base, MobileBase)
        with pytest.raises(RuntimeError, match="before any was logged"):
            base.state()
        state = ConstantBase().state()
        base.report(state)
        base.command(0.2, 0.1)
        base.stop()
        assert base.state() is state and base.last_command() == (0.2, 0.1)
        base.report(state)
        assert base.last_command() is None and base.commands == [(0.2, 0.1), (0.0, 0.0)]

    def test_differences(self) -> None:
        assert differs(0.5, 0.5, 0.0) == (False, 0.0)
        assert differs(0.5, 0.75, 0.1) == (True, 0.25)
        assert differs(0.5, 0.75, 0.3) == (False, 0.25)
        assert differs(None, 0.0, 1.0) == (True, None)
        assert differs(None, float("nan"), 0.0) == (False, None)
        assert differs("following", "arrived", 1.0) == (True, None)

    @pytest.mark.slow
    def test_cycles_without_a_frame_or_before_a_start_are_skipped(self, logged: Logged) -> None:
        memory = read_memory(logged.memory)
        state = ConstantBase().state()
        image = np.zeros((memory.camera.height, memory.camera.width), np.uint8)
        start = MissionStart(0, 2, np.random.default_rng(0).bit_generator.state,
                             dataclasses.replace(CONFIG, control=ControlConfig()))
        items = [LoggedCycle(0, state, image, True, None), start,
                 LoggedCycle(1, state, None, False, None), LoggedCycle(2, state, image, True, None)]
        report = replay(items, memory)
        assert (report.missions, report.skipped, report.fed_only, report.cycles) == (1, 2, 1, 0)
        with pytest.raises(InputError, match="is 80x60 px; the memory's camera takes 800x600"):
            replay([start, LoggedCycle(1, state, image[:60, :80], True, None)], memory)
