"""GoalRuns: the goals the robot works on and the mission run to the current one.

The runtime (:class:`robot.runtime.RobotRuntime`) decides when goals start and runs
end (:mod:`robot.modes`); this holds what that leaves behind: the goals (the
uploaded mission's, from its started item, or a photo's one key image), the
:class:`~robot.mission_run.MissionRun` to the current goal, the items reached, how
the last run ended, and the follower's state for the telemetry. Loop thread only.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.memory.localize import Localizer
from robot.mission import MissionState
from robot.mission_run import CycleRecord, MissionResult, MissionRun, start_run
from robot.runtime_log import RuntimeLog
from robot.vehicle.app_port import ServoTelemetry, VehicleTelemetry
from shared.interfaces import MobileBase
from shared.mavlink.mission.goal import Goal
from shared.memory import VisualMemory


@dataclass(eq=False)
class _Goals:
    """The goals being worked on: the uploaded mission's (``first_seq`` not None) or a photo's."""

    goals: tuple[Goal, ...]
    first_seq: int | None
    index: int = 0
    reached: tuple[int, ...] = ()


class GoalRuns:
    """The goals and their runs (module docstring).

    Args:
        base: the mobile base the runs drive.
        rng: seeds each run's own generator (its RANSAC samples), whose state the log
            records for replay.
        log: the field log; None records nothing.
        stopwatch: wall-time counter for the cycles' compute time, ns.
    """

    def __init__(self, base: MobileBase, rng: np.random.Generator, log: RuntimeLog | None,
                 stopwatch: Callable[[], int] = time.perf_counter_ns) -> None:
        self._base = base
        self._rng = rng
        self._log = log
        self._stopwatch = stopwatch
        self._goals: _Goals | None = None
        self._run: MissionRun | None = None
        self._events_seen = 0
        self.count = 0
        """Runs started so far."""
        self.last_result: MissionResult | None = None
        """How the last run ended; None before one ended."""
        self._last_state = MissionState.IDLE
        self._detail = ""
        self.servo: ServoTelemetry | None = None
        """The follower's state while a run follows; None otherwise."""

    @property
    def run(self) -> MissionRun | None:
        """The run to the current goal; None between runs."""
        return self._run

    def set_goals(self, goals: tuple[Goal, ...], first_seq: int | None) -> None:
        """Work on ``goals`` from the first (``first_seq``: its mission item; None: a photo's)."""
        self._goals = _Goals(goals, first_seq)

    def next_goal(self) -> None:
        """Move on to the next goal (after an arrival with goals left)."""
        assert self._goals is not None
        self._goals.index += 1

    def start(self, t_ns: int, memory: VisualMemory, localizer: Localizer,
              config: VmnavConfig) -> None:
        """Start the run to the current goal.

        Raises:
            VmnavError: the goal is not in ``memory`` (it left since the goals were checked).
        """
        goals = self._goals
        assert goals is not None
        goal = goals.goals[goals.index].key_image_id
        rng = np.random.default_rng(self._rng.integers(2**63))  # the run's alone: replayable
        if self._log is not None:
            self._log.mission_started(t_ns, goal, rng.bit_generator.state, config)
        run = start_run(memory, config, self._base, rng, goal, t_ns, localizer=localizer,
                        stopwatch=self._stopwatch)
        self._run, self._events_seen, self.servo = run, 0, None
        self.count += 1
        self._forward_events(run)

    def cycle(self, t_ns: int, image: npt.NDArray[np.uint8]) -> tuple[CycleRecord, bool | None]:
        """One cycle of the run on an (H, W) uint8 frame.

        Returns:
            The cycle, and None while the run goes on, else whether it arrived with
            goals left (:meth:`finish` was done).
        """
        run = self._run
        assert run is not None
        record = run.cycle(t_ns, image)
        if record.follow is not None:
            self.servo = _servo_telemetry(record)
        if self._log is not None:
            self._log.cycle(record, image)
        self._forward_events(run)
        return record, self.finish() if run.finished else None

    def end(self, t_ns: int, cause: str, why: str) -> None:
        """Abort the run for ``cause`` (:data:`robot.mission.ABORT_CAUSES`; ``why``: the
        detail line) and keep how it ended."""
        run = self._run
        assert run is not None
        run.abort(t_ns, cause, why)
        self._forward_events(run)
        self.finish()

    def abort(self, t_ns: int, why: str) -> None:
        """Abort the run, if any, and keep nothing (the robot process is closing)."""
        if self._run is not None:
            self._run.abort(t_ns, "shutdown", why)

    def finish(self) -> bool:
        """Keep how the finished run ended; True when it arrived with goals left."""
        goals, run = self._goals, self._run
        assert goals is not None and run is not None
        result = self.last_result = run.result()
        self._detail = _detail(result)
        self._run = None
        if result.state is MissionState.ARRIVED:
            if goals.first_seq is not None:
                goals.reached += (goals.first_seq + goals.index,)
            if goals.index + 1 < len(goals.goals):
                return True
        self._last_state = result.state
        return False

    def with_goals(self, t: VehicleTelemetry) -> VehicleTelemetry:
        """``t`` with the fields of the goals and their runs."""
        run, goals = self._run, self._goals
        state, detail = ((run.state, _detail(run.result())) if run is not None
                         else (self._last_state, self._detail))
        return replace(
            t, mission_state=state, mission_detail=detail,
            goal_key=None if goals is None else goals.goals[-1].key_image_id,
            servo=self.servo if run is not None else None,
            mission_seq=(None if goals is None or goals.first_seq is None
                         else goals.first_seq + min(goals.index, len(goals.goals) - 1)),
            reached_seqs=() if goals is None else goals.reached, run_count=self.count)

    def _forward_events(self, run: MissionRun) -> None:
        events = run.events
        if self._log is not None:
            for event in events[self._events_seen:]:
                self._log.event(event)
        self._events_seen = len(events)


def _detail(result: MissionResult) -> str:
    """The detail line of a run's last transition, led by its reason code unless the line
    already starts with it ("blocked for 60.0 s: holding")."""
    if not result.detail:
        return result.reason
    if result.detail.startswith(result.reason):
        return result.detail
    return f"{result.reason}: {result.detail}"


def _servo_telemetry(record: CycleRecord) -> ServoTelemetry:
    """The follower's state of a following cycle, for VISUAL_SERVO_STATUS."""
    follow, targets = record.follow, record.targets
    assert follow is not None and targets
    vision = follow.vision
    nan = math.nan
    return ServoTelemetry(
        current_key=targets[follow.target_index - 1] if follow.target_index > 0 else None,
        next_key=record.target_key,
        matches=0 if vision is None else vision.matches,
        err_image_max_px=nan if vision is None else vision.image_errors.err_image_max_px,
        err_points_px=nan if vision is None else vision.image_errors.err_points_px,
        y_m=nan if follow.y_m is None else follow.y_m,
        theta_rad=nan if follow.theta_rad is None else follow.theta_rad,
        s_m=nan if follow.s_m is None else follow.s_m)
