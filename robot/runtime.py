"""RobotRuntime: the robot process's application: modes, teleoperation, teaching, missions.

The runtime is the :class:`~robot.vehicle.app_port.VehicleApp` behind the MAVLink
vehicle, and the loop's one call per camera frame. It drives a
:class:`shared.interfaces.MobileBase` and keeps the visual memory of ``memory_dir``.

Theory of operation
-------------------

Three threads meet here. The link thread (the vehicle endpoint's) calls the
``VehicleApp`` methods; they decide at once from the last telemetry snapshot whether
the request can be taken (the ground station gets ACCEPTED or DENIED), and queue it
as an event of :mod:`robot.modes`. The loop thread calls :meth:`RobotRuntime.step`
with each frame (or :meth:`RobotRuntime.stall` when frames stop); each call first
takes the worker's finished results, then the queued requests, then what it sees of
the base, each an event fed to the transition table (:func:`robot.modes.decide`),
whose actions it carries out; then it does what the state says on this frame
(:func:`robot.modes.drive_of`) and publishes a new snapshot. The worker thread
(:class:`robot.worker.Worker`) reads and localizes photos and stores taught paths,
so the loop never waits on a disk or a localization; its results come back as
events on a later frame (in lock-step, exactly the next one: ``lockstep``). Only the
loop thread touches the base, the missions and the memory reference; the link thread
reads immutable snapshots and the memory reference, which teaching replaces whole
(never mutated in place). A request shows in the telemetry from the next frame on.

Rules: :mod:`robot.modes` holds the decisions (modes, arming, teaching, goal runs,
failsafes, photo goals) in one table; what they rest on here:

1. MANUAL drives by MANUAL_CONTROL (``x`` forward, ``r`` yaw clockwise, scaled by
   ``TeleopConfig``); no MANUAL_CONTROL for ``deadman_ns`` stops it.
2. AUTO runs the uploaded mission's goals in order, one
   :class:`~robot.mission_run.MissionRun` each (:class:`~robot.goal_runs.GoalRuns`),
   from the item the ground started; GUIDED, the one goal found from a photo
   (:meth:`goto_image`). A bumper or stall ends a run (its rule); in MANUAL the
   operator sees the base state in the telemetry and keeps control.
3. Disarming during a mission run needs ``force`` (refused on the link thread).
4. While teaching, every frame goes to a :class:`~robot.teach.KeyImageSelector`
   with the odometry. Stopping it hands the key images to the worker, which makes
   them a new path of the memory, joined to the others and written atomically to
   ``memory_dir`` (:func:`robot.worker.store_path`); the runtime then works on the
   new memory. A drive shorter than ``TeachConfig.min_path_length_m``, or a memory
   that cannot be written, is reported and nothing stored changes. Meanwhile the
   telemetry carries the thumbnail of each key image taken, with the id it gets when
   stored (``VehicleTelemetry.teach_thumbnails``), so the ground sees them come.
5. A photo goal is read and localized in the memory by the worker
   (:func:`robot.worker.find_photo`): found, the robot goes there in GUIDED; not found
   (or an unreadable photo, or one of another size than the camera's) is a notice.
   Either way, and when the loop refuses the photo or its goal, the outcome is kept
   for :meth:`next_job_outcome` (the command's final answer on the link), as is a
   taught path's (rule 4: stored, not stored, or the stop refused).
6. Frames stopping (:meth:`stall`): the base stops and nothing else changes; the
   mission run carries on with the next frame.
7. Notices for the operator (:meth:`next_notice`) tell what the telemetry cannot:
   paths saved, photos found or not, refusals decided in the loop, camera stalls, the
   base going quiet and coming back.
8. The base not reporting (``BaseState.reporting`` False: a cut ARIA cable): the robot
   stops (its commands may not arrive; the Pioneer's watchdog stops it too), teaching
   skips those frames (the odometry is frozen), and a mission run follows
   ``MissionConfig.base_lost_action``: "hold" ends it (HOLD, as an abort), "continue"
   pauses it until the base reports again.
9. The safety layer: the runtime drives the base only through a
   :class:`~robot.safe_base.SafeBase` it builds itself, so missions and the stick alike
   are bounded by the sonars and bumpers (``robot.safety``). A forced disarm is the
   emergency stop (QGroundControl's and ArduRover's: COMPONENT_ARM_DISARM with param2
   21196): the link thread stops the base on receipt (the Pioneer's E_STOP) and the
   hold lasts until the operator arms again (the robot stays disarmed until then). A
   bumper's hold ends when the operator, armed, changes mode, sends a goal or starts
   teaching.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.goal_runs import GoalRuns
from robot.memory.localize import Localizer
from robot.mission_run import CycleRecord, MissionResult
from robot.mode_events import (
    TOLD,
    Arm,
    BaseBack,
    BaseLost,
    Event,
    GcsLost,
    GoalGone,
    GotoPhoto,
    PathNotStored,
    PathStored,
    PhotoFound,
    PhotoNotFound,
    RunEnded,
    SetMode,
    StartGoals,
    TeachStart,
    TeachStop,
    TimeLimit,
)
from robot.modes import Action, Activity, Decision, Drive, TopState, decide, drive_of
from robot.runtime_log import RuntimeLog
from robot.safe_base import SafeBase
from robot.teach import KeyImageSelector, SelectedKeyImage
from robot.vehicle.app_port import (
    ACTIVE_STATES,
    GcsLostAction,
    Job,
    JobOutcome,
    VehicleTelemetry,
)
from robot.worker import Worker, find_photo, store_path
from shared.clock import Clock
from shared.errors import VmnavError
from shared.interfaces import BaseState, MobileBase
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.mission.items import MissionRefusal
from shared.mavlink.modes import Mode
from shared.memory import VisualMemory
from shared.memory.store import thumbnail_png
from shared.pose import Pose2

#: Notices queued at most (the oldest go first when the link does not take them).
_MAX_NOTICES = 64
#: Events that end (or refuse) a job whose outcome the link waits for (rules 4, 5).
_JOB_EVENTS = (GotoPhoto, PhotoFound, PhotoNotFound, TeachStop, PathStored, PathNotStored)


@dataclass(eq=False)
class _Teaching:
    name: str
    selector: KeyImageSelector
    key_images: list[SelectedKeyImage]
    first_id: int  #: the id the first key image gets when the path is stored
    thumbnails: tuple[tuple[int, bytes], ...] = ()  #: (id to be, PNG) of each taken so far


class RobotRuntime:
    """The robot's application (module rules).

    Args:
        memory: the visual memory, as loaded from ``memory_dir`` (or empty).
        memory_dir: where the memory lives; taught paths are written there.
        config: every component's settings (the vehicle endpoint replaces it through
            :meth:`params_changed`).
        base: the mobile base.
        clock: the loop's clock (the dead-man times MANUAL_CONTROL on it).
        rng: seeds each mission run's own generator (its RANSAC samples), whose state the
            log records for replay.
        log: the field log; None records nothing.
        stopwatch: wall-time counter for the cycles' compute time, ns.
        lockstep: the loop runs on a simulated clock: the worker's results land exactly
            one frame after their job (:class:`robot.worker.Worker`), the same on every run.
    """

    def __init__(self, memory: VisualMemory, memory_dir: Path, config: VmnavConfig,
                 base: MobileBase, clock: Clock, rng: np.random.Generator, *,
                 log: RuntimeLog | None = None,
                 stopwatch: Callable[[], int] = time.perf_counter_ns,
                 lockstep: bool = False) -> None:
        self._memory = memory
        self._memory_dir = memory_dir
        self._config = config
        self._base = SafeBase(base, clock, config.safety)
        self._clock = clock
        self._log = log
        self._localizer = Localizer.from_memory(memory, config.camera.mount, config.features,
                                                config.localize)
        self._worker = Worker(lockstep)
        self._requests: deque[Event] = deque()
        self._notices: deque[tuple[int, str]] = deque(maxlen=_MAX_NOTICES)
        self._job_outcomes: deque[JobOutcome] = deque(maxlen=_MAX_NOTICES)
        self._manual: tuple[float, float, int] | None = None  # (x, r, arrival ns)
        self._top = TopState()
        self._goals = GoalRuns(self._base, rng, log, stopwatch)
        self._teaching: _Teaching | None = None
        self._twist = (0.0, 0.0)
        self._home: Pose2 | None = None
        self._stalled_since_ns: int | None = None
        self._base_lost_since_ns: int | None = None
        self._snapshot = VehicleTelemetry(mode=self._top.mode, armed=self._top.armed)
        if not config.safety.enabled:
            self._say(clock.now_ns(), logging.WARNING,
                      "safety layer off ([safety] enabled = false): sonars and bumpers do "
                      "not bound the speed")

    @property
    def last_result(self) -> MissionResult | None:
        """How the last mission run ended; None before one ended."""
        return self._goals.last_result

    @property
    def memory(self) -> VisualMemory:
        """The memory in force (replaced whole when a taught path joins it)."""
        return self._memory

    # -- the loop's side ----------------------------------------------------------------

    def step(self, t_ns: int, image: npt.NDArray[np.uint8]) -> CycleRecord | None:
        """One frame: the news (worker, requests, base), then the state's work.

        Args:
            t_ns: the frame's time on the loop's clock, ns.
            image: (H, W) uint8 grey frame.

        Returns:
            The mission cycle when a mission run drove the robot on this frame; else None.
        """
        if self._stalled_since_ns is not None:
            self._say(t_ns, logging.INFO, f"camera back after "
                                          f"{(t_ns - self._stalled_since_ns) / 1e9:.1f} s")
            self._stalled_since_ns = None
        base = self._base.state()
        if self._home is None and base.reporting:
            self._home = base.odom_pose
        self._take_news(t_ns, base)
        record = None
        drive = drive_of(self._top)
        if drive is Drive.RUN:
            record = self._cycle(t_ns, image)
        elif drive is Drive.STICK:
            self._drive_manual()
        else:
            self._stop()
        if self._teaching is not None and not self._top.base_lost:
            self._teach_frame(self._teaching, t_ns, image, base)
        self._publish(base)
        return record

    def stall(self, now_ns: int) -> None:
        """No frame came in time: stop the base, keep everything else (rule 7)."""
        if self._stalled_since_ns is None:
            self._stalled_since_ns = now_ns
            self._say(now_ns, logging.WARNING, "camera stalled: stopped until frames return")
        base = self._base.state()
        self._take_news(now_ns, base)
        self._stop()
        self._publish(base)

    def close(self) -> None:
        """Stop the base; a mission run ends as the operator's abort; teaching is dropped;
        the worker finishes the job in progress (a path being written) and stops."""
        now_ns = self._clock.now_ns()
        self._goals.abort(now_ns, "the robot process is closing")
        if self._teaching is not None:
            self._say(now_ns, logging.WARNING,
                      f"teach {self._teaching.name!r} dropped: the robot process is closing")
            self._teaching = None
        self._stop()
        self._worker.close()

    # -- VehicleApp (the link thread's side) ------------------------------------------

    def telemetry(self) -> VehicleTelemetry:
        return self._snapshot

    def validate_goals(self, goals: tuple[Goal, ...]) -> MissionRefusal | None:
        """Every goal is a key image of the memory, and each leg between consecutive goals
        has a route. Where the robot stands is checked when it localizes (a robot may have
        been carried since its last key image): a first goal out of reach then ends the run."""
        memory = self._memory
        previous: int | None = None
        for seq, goal in enumerate(goals):
            key = goal.key_image_id
            if key not in memory.keyframes:
                return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM1,
                                      f"item {seq}: no key image {key} in the memory")
            if previous is not None and not memory.plan_route(previous, key):
                return MissionRefusal(mavlink.MAV_MISSION_DENIED,
                                      f"item {seq}: no route from key image {previous} to {key}")
            previous = key
        return None

    def set_mode(self, mode: Mode) -> bool:
        if mode is Mode.AUTO:
            return False
        self._requests.append(SetMode(mode))
        return True

    def arm(self, armed: bool, force: bool) -> bool:
        if not armed and not force and self._snapshot.mission_state in ACTIVE_STATES:
            return False
        emergency = not armed and force
        if emergency:
            self._base.emergency_stop()  # rule 9: now, not on the loop's next frame
        self._requests.append(Arm(armed, emergency))
        return True

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        if self._snapshot.teaching or not self._snapshot.armed or not goals:
            return False
        self._requests.append(StartGoals(goals, first_seq))
        return True

    def goto_image(self, path: Path) -> bool:
        if self._snapshot.teaching or not self._snapshot.armed:
            return False
        self._requests.append(GotoPhoto(path))
        return True

    def params_changed(self, config: VmnavConfig) -> None:
        self._config = config
        self._base.configure(config.safety)

    def manual_control(self, x: float, y: float, z: float, r: float, buttons: int,
                       now_ns: int) -> None:
        self._manual = (_stick(x), _stick(r), self._clock.now_ns())

    def teach_start(self, name: str) -> bool:
        t = self._snapshot
        if t.teaching or t.mission_state in ACTIVE_STATES:
            return False
        self._requests.append(TeachStart(name))
        return True

    def teach_stop(self) -> bool:
        if not self._snapshot.teaching:
            return False
        self._requests.append(TeachStop())
        return True

    def time_limit(self, text: str) -> None:
        """A supervisor's time limit ran out (a benchmark, a test rig): a run in progress
        ends in HOLD with the cause ``time_limit`` and ``text``; safe from any thread."""
        self._requests.append(TimeLimit(text))

    def gcs_lost(self, action: GcsLostAction) -> None:
        self._requests.append(GcsLost(action))

    def gcs_regained(self) -> None:
        """Nothing to undo: the robot stays where the failsafe left it."""

    def next_notice(self) -> tuple[int, str] | None:
        try:
            return self._notices.popleft()
        except IndexError:
            return None

    def next_job_outcome(self) -> JobOutcome | None:
        try:
            return self._job_outcomes.popleft()
        except IndexError:
            return None

    # -- events -------------------------------------------------------------------------

    def _take_news(self, t_ns: int, base: BaseState) -> None:
        """The worker's results, the queued requests, then the base's reporting (rule 8)."""
        for result in self._worker.results():
            self._handle(t_ns, result)
        while self._requests:
            self._handle(t_ns, self._requests.popleft())
        if not base.reporting and not self._top.base_lost:
            self._base_lost_since_ns = t_ns
            self._handle(t_ns, BaseLost(self._config.mission.base_lost_action == "hold"))
        elif base.reporting and self._top.base_lost:
            self._handle(t_ns, BaseBack())
            self._base_lost_since_ns = None

    def _handle(self, t_ns: int, event: Event) -> None:
        """Feed ``event`` to the table and carry out its decision."""
        decision = decide(self._top, event)
        self._top = decision.state
        if (isinstance(event, Arm) and event.armed) or (
                isinstance(event, SetMode | StartGoals | PhotoFound | TeachStart)
                and self._top.armed and not decision.refused):
            self._base.release()  # rule 9: the operator acted
        for action in decision.actions:
            self._act(action, t_ns, event, decision)
        if isinstance(event, _JOB_EVENTS):
            self._job_outcome(event, decision)  # after its notice (rules 4, 5)

    def _act(self, action: Action, t_ns: int, event: Event, decision: Decision) -> None:
        match action:
            case Action.SAY:
                self._say(t_ns, logging.WARNING, decision.say)
            case Action.SAY_EVENT:
                assert isinstance(event, TOLD)
                self._say(t_ns, event.level, event.text)
            case Action.SAY_BASE_BACK:
                assert self._base_lost_since_ns is not None
                resumes = ", mission resumes" if self._top.activity is Activity.RUNNING else ""
                self._say(t_ns, logging.INFO, f"base reporting again after "
                          f"{(t_ns - self._base_lost_since_ns) / 1e9:.1f} s{resumes}")
            case Action.END_RUN:
                self._goals.end(t_ns, decision.cause, decision.why)
                self._stop()
            case Action.SAY_MODE:
                self._say(t_ns, logging.INFO, f"mode {self._top.mode.name}")
            case Action.DROP_STICK:
                self._manual = None
            case Action.START_GOALS:
                assert isinstance(event, StartGoals)
                self._goals.set_goals(event.goals, event.first_seq)
                self._start_run(t_ns)
            case Action.NEXT_GOAL:
                self._goals.next_goal()
                self._start_run(t_ns)
            case Action.START_PHOTO_GOAL:
                assert isinstance(event, PhotoFound)
                self._goals.set_goals((Goal(event.goal_key),), None)
                self._start_run(t_ns)
            case Action.FIND_PHOTO:
                assert isinstance(event, GotoPhoto)
                self._worker.submit(find_photo, event.path, self._localizer, self._memory.camera)
            case Action.START_TEACH:
                assert isinstance(event, TeachStart)
                self._teach_start(t_ns, event.name)
            case Action.SAVE_PATH:
                self._save_path()
            case Action.ADOPT_MEMORY:
                assert isinstance(event, PathStored)
                self._memory, self._localizer = event.memory, event.localizer
            case Action.STOP:
                self._stop()

    # -- missions -----------------------------------------------------------------------

    def _start_run(self, t_ns: int) -> None:
        try:
            self._goals.start(t_ns, self._memory, self._localizer, self._config)
        except VmnavError as e:  # the goal left the memory since the upload was checked
            self._handle(t_ns, GoalGone(f"mission: {e}"))

    def _cycle(self, t_ns: int, image: npt.NDArray[np.uint8]) -> CycleRecord:
        record, next_goal = self._goals.cycle(t_ns, image)
        if record.follow is not None:
            self._twist = (record.follow.twist.v_m_s, record.follow.twist.omega_rad_s)
        if next_goal is not None:
            self._handle(t_ns, RunEnded(next_goal))
        return record

    # -- driving ------------------------------------------------------------------------

    def _drive_manual(self) -> None:
        manual = self._manual
        teleop = self._config.teleop
        if manual is None or self._clock.now_ns() - manual[2] > teleop.deadman_ns:
            self._stop()
            return
        x, r, _ = manual
        self._twist = (x * teleop.max_speed_m_s, -r * teleop.max_omega_rad_s)
        self._base.command(*self._twist)

    def _stop(self) -> None:
        self._twist = (0.0, 0.0)
        self._base.stop()

    # -- teaching -----------------------------------------------------------------------

    def _teach_start(self, t_ns: int, name: str) -> None:
        name = name or f"path-{len(self._memory.paths) + 1}"
        config = self._config
        selector = KeyImageSelector(self._memory.camera, config.features, config.teach)
        self._teaching = _Teaching(name, selector, [], max(self._memory.keyframes, default=-1) + 1)
        self._say(t_ns, logging.INFO, f"teaching {name!r}: drive the route in MANUAL")

    def _teach_frame(self, teaching: _Teaching, t_ns: int, image: npt.NDArray[np.uint8],
                     base: BaseState) -> None:
        if self._log is not None:
            self._log.teach_frame(t_ns, image, base.odom_pose)
        taken = teaching.selector.push(t_ns, image, base.odom_pose)
        for key_image in taken:  # shown by the ground as they come (rule 4)
            teaching.thumbnails += ((teaching.first_id + len(teaching.thumbnails),
                                     thumbnail_png(key_image.record.image)),)
        teaching.key_images += taken

    def _save_path(self) -> None:
        """Hand the taught key images to the worker (rule 4)."""
        teaching = self._teaching
        assert teaching is not None
        self._teaching = None
        key_images = teaching.key_images + list(teaching.selector.finish())
        self._worker.submit(store_path, self._memory_dir, self._memory.camera, teaching.name,
                            tuple(k.record for k in key_images), self._config)

    # -- output -------------------------------------------------------------------------

    def _job_outcome(self, event: Event, decision: Decision) -> None:
        """Where a photo goal or a taught path ended up (rules 4, 5), for the command's
        final answer."""
        job: Job = "photo" if isinstance(event, GotoPhoto | PhotoFound | PhotoNotFound) else "path"
        if decision.refused:
            self._job_outcomes.append(JobOutcome(job, None, decision.say))
        elif isinstance(event, PhotoFound):
            self._job_outcomes.append(JobOutcome(job, event.goal_key, event.text))
        elif isinstance(event, PathStored):
            self._job_outcomes.append(JobOutcome(job, event.path_id, event.text))
        elif isinstance(event, PhotoNotFound | PathNotStored):
            self._job_outcomes.append(JobOutcome(job, None, event.text))

    def _say(self, t_ns: int, level: int, text: str) -> None:
        self._notices.append((level, text))
        if self._log is not None:
            self._log.note(t_ns, level, text)

    def _publish(self, base: BaseState) -> None:
        top = self._top
        self._snapshot = self._goals.with_goals(VehicleTelemetry(
            mode=top.mode, armed=top.armed, teaching=self._teaching is not None,
            teach_thumbnails=() if self._teaching is None else self._teaching.thumbnails,
            battery_v=base.battery_v, odom_pose=base.odom_pose, velocity=self._twist,
            home_pose=self._home, base_reporting=not top.base_lost))


def _stick(value: float) -> float:
    """A MANUAL_CONTROL axis in [-1, 1]; an unused (NaN) axis is 0."""
    return 0.0 if math.isnan(value) else min(1.0, max(-1.0, value))
