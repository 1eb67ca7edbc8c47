"""RobotRuntime: the robot process's application: modes, teleoperation, teaching, missions.

The runtime is the :class:`~robot.vehicle.app_port.VehicleApp` behind the MAVLink
vehicle, and the loop's one call per camera frame. It drives a
:class:`shared.interfaces.MobileBase` and keeps the visual memory of ``memory_dir``.

Theory of operation
-------------------

Two threads meet here. The link thread (the vehicle endpoint's) calls the
``VehicleApp`` methods; they decide at once from the last telemetry snapshot whether
the request can be taken (the ground station gets ACCEPTED or DENIED), and queue it.
The loop thread calls :meth:`RobotRuntime.step` with each frame (or
:meth:`RobotRuntime.stall` when frames stop); each call first applies the queued
requests in order, then does what the mode says, then publishes a new snapshot.
Only the loop thread touches the base, the missions and the memory; the link thread
reads immutable snapshots and the memory reference, which teaching replaces whole
(never mutated in place). A request shows in the telemetry from the next frame on.

Rules:

1. Modes (ArduRover's): the robot starts in HOLD, armed. HOLD: stopped. MANUAL:
   driven by MANUAL_CONTROL (``x`` forward, ``r`` yaw clockwise, scaled by
   ``TeleopConfig``); no MANUAL_CONTROL for ``deadman_ns`` stops it. AUTO: the
   uploaded mission's goals in order, one :class:`~robot.mission_run.MissionRun`
   each, from the item the ground started; after the last goal, or when a mission
   run fails or aborts, the robot stops in HOLD. GUIDED: one goal found from a photo
   (:meth:`goto_image`), then HOLD; GUIDED without a goal is stopped.
2. Leaving AUTO or GUIDED for another mode (or the GCS failsafe's "hold") aborts the
   mission run as the operator's abort; AUTO again restarts from the current item.
3. Disarmed, the robot does not move in any mode; disarming during a mission run
   needs ``force``; missions and photo goals are refused while disarmed.
4. Teaching (``teach_start``/``teach_stop``) is refused during a mission run and
   puts the robot in MANUAL; every frame while teaching goes to a
   :class:`~robot.teach.KeyImageSelector` with the odometry. Stopping it (in any
   mode) makes the key images a new path of the memory, joined to the others
   (:func:`robot.memory.junctions.join_path`) and written atomically to
   ``memory_dir``; the runtime then works on the new memory. A drive shorter than
   ``TeachConfig.min_path_length_m``, or a memory that cannot be written, is
   reported and nothing stored changes.
5. A photo goal is localized in the memory (:class:`robot.memory.localize.Localizer`)
   on the next frame; found, the robot goes there in GUIDED; not found (or an
   unreadable photo, or one of another size than the camera's) is a notice and
   nothing moves.
6. A bumper or stall ends a mission run (its rule); in MANUAL the operator sees the
   base state in the telemetry and keeps control.
7. Frames stopping (:meth:`stall`): the base stops and nothing else changes; the
   mission run carries on with the next frame.
8. Notices for the operator (:meth:`next_notice`) tell what the telemetry cannot:
   paths saved, photos found or not, refusals decided in the loop, camera stalls, the
   base going quiet and coming back.
9. The base not reporting (``BaseState.reporting`` False: a cut ARIA cable): the robot
   stops (its commands may not arrive; the Pioneer's watchdog stops it too), teaching
   skips those frames (the odometry is frozen), and a mission run follows
   ``MissionConfig.base_lost_action``: "hold" ends it (HOLD, as an abort), "continue"
   pauses it until the base reports again.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.memory.junctions import join_path
from robot.memory.localize import Localizer
from robot.mission import MissionState
from robot.mission_run import AppEvent, CycleRecord, MissionResult, MissionRun
from robot.teach import KeyImageSelector, OdomPose, SelectedKeyImage
from robot.vehicle.app_port import ACTIVE_STATES, GcsLostAction, ServoTelemetry, VehicleTelemetry
from shared.clock import Clock
from shared.errors import VmnavError
from shared.interfaces import BaseState, MobileBase
from shared.mavlink.dialect import mavlink
from shared.mavlink.goal import Goal
from shared.mavlink.mission_items import MissionRefusal
from shared.mavlink.modes import Mode
from shared.memory import VisualMemory, read_memory, write_memory
from shared.memory.store import check_no_orphans

#: Modes in which a mission run drives the robot.
_MISSION_MODES = frozenset({Mode.AUTO, Mode.GUIDED})
#: Notices queued at most (the oldest go first when the link does not take them).
_MAX_NOTICES = 64


class RuntimeLog(Protocol):
    """Where the runtime records what it does (the robot's field log)."""

    def mission_started(self, t_ns: int, goal_id: int, rng_state: Any,
                        config: VmnavConfig) -> None:
        """A mission run to ``goal_id`` starts; ``rng_state`` is its generator's state."""
        ...

    def cycle(self, record: CycleRecord, image: npt.NDArray[np.uint8],
              targets: Sequence[int] = ()) -> None:
        """One mission cycle on its (H, W) uint8 frame; ``targets``: the route's key images."""
        ...

    def event(self, event: AppEvent) -> None:
        """A mission event (transition, key image, localization, lost)."""
        ...

    def teach_frame(self, t_ns: int, image: npt.NDArray[np.uint8], odom_pose: OdomPose) -> None:
        """A frame recorded while teaching, with the odometry (x_m, y_m, yaw_rad)."""
        ...

    def note(self, t_ns: int, level: int, text: str) -> None:
        """Anything else for the operator (``logging`` level, one line)."""
        ...


@dataclass(frozen=True, slots=True)
class _SetMode:
    mode: Mode


@dataclass(frozen=True, slots=True)
class _Arm:
    armed: bool


@dataclass(frozen=True, slots=True)
class _StartMission:
    goals: tuple[Goal, ...]
    first_seq: int


@dataclass(frozen=True, slots=True)
class _GotoImage:
    path: Path


@dataclass(frozen=True, slots=True)
class _TeachStart:
    name: str


@dataclass(frozen=True, slots=True)
class _TeachStop:
    pass


_Request = _SetMode | _Arm | _StartMission | _GotoImage | _TeachStart | _TeachStop


@dataclass(eq=False)
class _Teaching:
    name: str
    selector: KeyImageSelector
    key_images: list[SelectedKeyImage]


@dataclass(eq=False)
class _Mission:
    """The goals being worked on: the uploaded mission's (``first_seq`` not None) or a photo's."""

    goals: tuple[Goal, ...]
    first_seq: int | None
    index: int = 0
    reached: tuple[int, ...] = ()


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
    """

    def __init__(self, memory: VisualMemory, memory_dir: Path, config: VmnavConfig,
                 base: MobileBase, clock: Clock, rng: np.random.Generator, *,
                 log: RuntimeLog | None = None,
                 stopwatch: Callable[[], int] = time.perf_counter_ns) -> None:
        self._memory = memory
        self._memory_dir = memory_dir
        self._config = config
        self._base = base
        self._clock = clock
        self._rng = rng
        self._log = log
        self._stopwatch = stopwatch
        self._localizer = Localizer.from_memory(memory, config.features, config.localize)
        self._requests: deque[_Request] = deque()
        self._notices: deque[tuple[int, str]] = deque(maxlen=_MAX_NOTICES)
        self._manual: tuple[float, float, int] | None = None  # (x, r, arrival ns)
        self._mode = Mode.HOLD
        self._armed = True
        self._run: MissionRun | None = None
        self._events_seen = 0
        self._mission: _Mission | None = None
        self._teaching: _Teaching | None = None
        self._detail = ""
        self._last_state = MissionState.IDLE
        self._last_result: MissionResult | None = None
        self._servo: ServoTelemetry | None = None
        self._twist = (0.0, 0.0)
        self._home: OdomPose | None = None
        self._stalled_since_ns: int | None = None
        self._base_lost_since_ns: int | None = None
        self._snapshot = VehicleTelemetry(mode=self._mode, armed=self._armed)

    @property
    def last_result(self) -> MissionResult | None:
        """How the last mission run ended; None before one ended."""
        return self._last_result

    @property
    def memory(self) -> VisualMemory:
        """The memory in force (replaced whole when a taught path joins it)."""
        return self._memory

    # -- the loop's side ----------------------------------------------------------------

    def step(self, t_ns: int, image: npt.NDArray[np.uint8]) -> CycleRecord | None:
        """One frame: queued requests, then the mode's work (module rules).

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
        self._apply_requests(t_ns, image)
        self._watch_base(t_ns, base)
        record = None
        if self._base_lost_since_ns is not None:
            self._stop()
        elif self._run is not None and self._mode in _MISSION_MODES and self._armed:
            record = self._cycle(self._run, t_ns, image)
        elif self._mode is Mode.MANUAL and self._armed:
            self._drive_manual(t_ns)
        else:
            self._stop()
        if self._teaching is not None and self._base_lost_since_ns is None:
            self._teach_frame(self._teaching, t_ns, image, base)
        self._publish(base)
        return record

    def stall(self, now_ns: int) -> None:
        """No frame came in time: stop the base, keep everything else (rule 7)."""
        if self._stalled_since_ns is None:
            self._stalled_since_ns = now_ns
            self._say(now_ns, logging.WARNING, "camera stalled: stopped until frames return")
        self._apply_requests(now_ns, None)
        base = self._base.state()
        self._watch_base(now_ns, base)
        self._stop()
        self._publish(base)

    def close(self) -> None:
        """Stop the base; a mission run ends as the operator's abort; teaching is dropped."""
        now_ns = self._clock.now_ns()
        if self._run is not None:
            self._run.abort(now_ns, "the robot process is closing")
        if self._teaching is not None:
            self._say(now_ns, logging.WARNING,
                      f"teach {self._teaching.name!r} dropped: the robot process is closing")
            self._teaching = None
        self._stop()

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
        self._requests.append(_SetMode(mode))
        return True

    def arm(self, armed: bool, force: bool) -> bool:
        if not armed and not force and self._snapshot.mission_state in ACTIVE_STATES:
            return False
        self._requests.append(_Arm(armed))
        return True

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        if self._snapshot.teaching or not self._snapshot.armed or not goals:
            return False
        self._requests.append(_StartMission(goals, first_seq))
        return True

    def goto_image(self, path: Path) -> bool:
        if self._snapshot.teaching or not self._snapshot.armed:
            return False
        self._requests.append(_GotoImage(path))
        return True

    def params_changed(self, config: VmnavConfig) -> None:
        self._config = config

    def manual_control(self, x: float, y: float, z: float, r: float, buttons: int,
                       now_ns: int) -> None:
        self._manual = (_stick(x), _stick(r), self._clock.now_ns())

    def teach_start(self, name: str) -> bool:
        t = self._snapshot
        if t.teaching or t.mission_state in ACTIVE_STATES:
            return False
        self._requests.append(_TeachStart(name))
        return True

    def teach_stop(self) -> bool:
        if not self._snapshot.teaching:
            return False
        self._requests.append(_TeachStop())
        return True

    def gcs_lost(self, action: GcsLostAction) -> None:
        if action == "stop":
            self._manual = None
        elif action == "hold":
            self._requests.append(_SetMode(Mode.HOLD))

    def gcs_regained(self) -> None:
        """Nothing to undo: the robot stays where the failsafe left it."""

    def next_notice(self) -> tuple[int, str] | None:
        try:
            return self._notices.popleft()
        except IndexError:
            return None

    # -- requests -----------------------------------------------------------------------

    def _apply_requests(self, t_ns: int, image: npt.NDArray[np.uint8] | None) -> None:
        while self._requests:
            request = self._requests.popleft()
            if isinstance(request, _SetMode):
                self._enter(request.mode, t_ns)
            elif isinstance(request, _Arm):
                self._armed = request.armed
                if not request.armed:
                    self._end_run(t_ns, "disarmed")
            elif isinstance(request, _StartMission):
                self._end_run(t_ns, "a new mission started")
                self._mission = _Mission(request.goals, request.first_seq)
                self._mode = Mode.AUTO
                self._start_run(t_ns)
            elif isinstance(request, _GotoImage):
                self._goto_image(t_ns, request.path)
            elif isinstance(request, _TeachStart):
                self._teach_start(t_ns, request.name)
            else:
                self._teach_stop(t_ns)

    def _enter(self, mode: Mode, t_ns: int) -> None:
        if mode is not self._mode:
            self._end_run(t_ns, f"mode {mode.name}")
            self._say(t_ns, logging.INFO, f"mode {mode.name}")
        self._mode = mode
        self._manual = None

    def _goto_image(self, t_ns: int, path: Path) -> None:
        camera = self._memory.camera
        photo = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if photo is None:
            self._say(t_ns, logging.ERROR, f"photo {path.name}: not a readable image")
            return
        if photo.shape != (camera.height, camera.width):
            self._say(t_ns, logging.ERROR,
                      f"photo {path.name}: {photo.shape[1]}x{photo.shape[0]} px, the camera's "
                      f"images are {camera.width}x{camera.height}")
            return
        found = self._localizer.localize(photo)
        if not found.ok or found.keyframe_id is None:
            self._say(t_ns, logging.WARNING,
                      f"photo {path.name}: not in the memory (best key image "
                      f"{found.keyframe_id}, {found.matches} matches)")
            return
        self._say(t_ns, logging.INFO, f"photo {path.name}: key image {found.keyframe_id} "
                                      f"({found.matches} matches), going there")
        self._end_run(t_ns, "a new goal")
        self._mission = _Mission((Goal(found.keyframe_id),), None)
        self._mode = Mode.GUIDED
        self._start_run(t_ns)

    # -- missions -----------------------------------------------------------------------

    def _start_run(self, t_ns: int) -> None:
        mission = self._mission
        assert mission is not None
        goal = mission.goals[mission.index].key_image_id
        rng = np.random.default_rng(self._rng.integers(2**63))  # the run's alone: replayable
        run = MissionRun(self._memory, self._config, self._base, rng,
                         localizer=self._localizer, stopwatch=self._stopwatch)
        if self._log is not None:
            self._log.mission_started(t_ns, goal, rng.bit_generator.state, self._config)
        try:
            run.start(goal, t_ns)
        except VmnavError as e:  # the goal left the memory since the upload was checked
            self._say(t_ns, logging.ERROR, f"mission: {e}")
            self._mode = Mode.HOLD
            return
        self._run, self._events_seen, self._servo = run, 0, None
        self._forward_events(run)

    def _cycle(self, run: MissionRun, t_ns: int, image: npt.NDArray[np.uint8]) -> CycleRecord:
        record = run.cycle(t_ns, image)
        follow = record.follow
        if follow is not None:
            self._twist = (follow.twist.v_m_s, follow.twist.omega_rad_s)
            self._servo = _servo_telemetry(run, record)
        if self._log is not None:
            self._log.cycle(record, image, () if run.follower is None else run.follower.targets)
        self._forward_events(run)
        if run.finished:
            self._run_finished(run, t_ns)
        return record

    def _run_finished(self, run: MissionRun, t_ns: int) -> None:
        mission = self._mission
        assert mission is not None
        result = self._last_result = run.result()
        self._detail = f"{result.reason}: {result.detail}" if result.detail else result.reason
        self._run = None
        if result.state is MissionState.ARRIVED:
            if mission.first_seq is not None:
                mission.reached += (mission.first_seq + mission.index,)
            if mission.index + 1 < len(mission.goals):
                mission.index += 1
                self._start_run(t_ns)
                return
        self._last_state = result.state
        self._mode = Mode.HOLD
        self._stop()

    def _end_run(self, t_ns: int, why: str) -> None:
        run = self._run
        if run is None:
            return
        run.abort(t_ns, why)
        self._forward_events(run)
        self._run_finished(run, t_ns)

    def _forward_events(self, run: MissionRun) -> None:
        events = run.events
        if self._log is not None:
            for event in events[self._events_seen:]:
                self._log.event(event)
        self._events_seen = len(events)

    # -- driving ------------------------------------------------------------------------

    def _watch_base(self, t_ns: int, base: BaseState) -> None:
        """Rule 9: notice the base going quiet and coming back; "hold" ends the run."""
        lost_since = self._base_lost_since_ns
        if not base.reporting and lost_since is None:
            self._base_lost_since_ns = t_ns
            if self._run is None:
                self._say(t_ns, logging.WARNING, "base not reporting: stopped")
            elif self._config.mission.base_lost_action == "hold":
                self._say(t_ns, logging.WARNING, "base not reporting: stopped, mission held")
                self._end_run(t_ns, "the base stopped reporting")
            else:
                self._say(t_ns, logging.WARNING, "base not reporting: stopped, mission paused")
        elif base.reporting and lost_since is not None:
            self._base_lost_since_ns = None
            resumes = ", mission resumes" if self._run is not None else ""
            self._say(t_ns, logging.INFO,
                      f"base reporting again after {(t_ns - lost_since) / 1e9:.1f} s{resumes}")

    def _drive_manual(self, t_ns: int) -> None:
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
        if self._run is not None:
            self._say(t_ns, logging.WARNING, "teach start refused: a mission is running")
            return
        name = name or f"path-{len(self._memory.paths) + 1}"
        config = self._config
        selector = KeyImageSelector(self._memory.camera, config.features, config.teach)
        self._teaching = _Teaching(name, selector, [])
        self._enter(Mode.MANUAL, t_ns)
        self._say(t_ns, logging.INFO, f"teaching {name!r}: drive the route in MANUAL")

    def _teach_frame(self, teaching: _Teaching, t_ns: int, image: npt.NDArray[np.uint8],
                     base: BaseState) -> None:
        if self._log is not None:
            self._log.teach_frame(t_ns, image, base.odom_pose)
        teaching.key_images += teaching.selector.push(t_ns, image, base.odom_pose)

    def _teach_stop(self, t_ns: int) -> None:
        teaching = self._teaching
        assert teaching is not None
        self._teaching = None
        self._stop()
        key_images = teaching.key_images + list(teaching.selector.finish())
        config = self._config
        length_m = key_images[-1].record.distance_m if key_images else 0.0
        if len(key_images) < 2 or length_m < config.teach.min_path_length_m:
            self._say(t_ns, logging.ERROR,
                      f"teach {teaching.name!r}: {length_m:.2f} m driven, a path needs "
                      f"{config.teach.min_path_length_m:.2f} m: nothing stored")
            return
        try:
            check_no_orphans(self._memory_dir)
            memory = (read_memory(self._memory_dir)
                      if (self._memory_dir / "manifest.json").exists()
                      else VisualMemory(self._memory.camera))
            path = memory.add_path(teaching.name, [k.record for k in key_images])
            attempts = join_path(memory, path, config.features, config.localize, config.teach)
            write_memory(self._memory_dir, memory)
        except (VmnavError, OSError) as e:
            self._say(t_ns, logging.ERROR, f"teach {teaching.name!r} not stored: {e}")
            return
        self._memory = memory
        self._localizer = Localizer.from_memory(memory, config.features, config.localize)
        joined = sum(a.accepted for a in attempts)
        self._say(t_ns, logging.INFO,
                  f"path {path.id} {teaching.name!r}: {len(key_images)} key images, "
                  f"{joined} junction(s)")

    # -- output -------------------------------------------------------------------------

    def _say(self, t_ns: int, level: int, text: str) -> None:
        self._notices.append((level, text))
        if self._log is not None:
            self._log.note(t_ns, level, text)

    def _publish(self, base: BaseState) -> None:
        run, mission = self._run, self._mission
        if run is not None:
            state, detail = run.state, _last_detail(run)
        else:
            state, detail = self._last_state, self._detail
        self._snapshot = VehicleTelemetry(
            mode=self._mode, mission_state=state, armed=self._armed, mission_detail=detail,
            teaching=self._teaching is not None, battery_v=base.battery_v,
            odom_pose=base.odom_pose, velocity=self._twist,
            goal_key=None if mission is None else mission.goals[-1].key_image_id,
            servo=self._servo if run is not None else None,
            mission_seq=(None if mission is None or mission.first_seq is None
                         else mission.first_seq + min(mission.index, len(mission.goals) - 1)),
            reached_seqs=() if mission is None else mission.reached,
            home_pose=self._home, base_reporting=self._base_lost_since_ns is None)


def _stick(value: float) -> float:
    """A MANUAL_CONTROL axis in [-1, 1]; an unused (NaN) axis is 0."""
    return 0.0 if math.isnan(value) else min(1.0, max(-1.0, value))


def _last_detail(run: MissionRun) -> str:
    """The detail of the run's last transition."""
    result = run.result()
    return f"{result.reason}: {result.detail}" if result.detail else result.reason


def _servo_telemetry(run: MissionRun, record: CycleRecord) -> ServoTelemetry:
    """The follower's state of a following cycle, for VISUAL_SERVO_STATUS."""
    follow = record.follow
    follower = run.follower
    assert follow is not None and follower is not None
    targets = follower.targets
    vision = follow.vision
    nan = math.nan
    return ServoTelemetry(
        current_key=targets[follow.target_index - 1] if follow.target_index > 0 else None,
        next_key=targets[min(follow.target_index, len(targets) - 1)],
        matches=0 if vision is None else vision.matches,
        err_image_max_px=nan if vision is None else vision.image_errors.err_image_max_px,
        err_points_px=nan if vision is None else vision.image_errors.err_points_px,
        y_m=nan if follow.y_m is None else follow.y_m,
        theta_rad=nan if follow.theta_rad is None else follow.theta_rad,
        s_m=nan if follow.s_m is None else follow.s_m)


