"""One mission to a goal key image, cycle by cycle: localize, plan, follow, arrive.

A :class:`MissionRun` owns the mission state machine (:class:`robot.mission.Mission`)
and, while following, the :class:`robot.follower.RouteFollower`; it commands a
:class:`shared.interfaces.MobileBase`. Whoever reads the camera calls
:meth:`MissionRun.cycle` with each frame: the robot's runtime
(:class:`robot.runtime.RobotRuntime`, between its other duties), or
:meth:`MissionRun.run`, a loop over a :class:`shared.interfaces.FrameSource` and a
:class:`shared.clock.Clock` (the simulator's in lock-step).

Rules of a cycle (:meth:`MissionRun.cycle`):

1. Read the base's state. A pressed bumper (unless the safety layer found the robot
   standing when it was pressed: someone walked into it) or a stall goes to the
   mission first (ABORTED); then the safety layer's hold (``BaseState.blocked``):
   following, a hold makes the mission wait (WAITING: the follower pauses, its
   estimate kept); waiting, its end resumes the route (the follower resumes where
   it stood, the time spent waiting not counted against its LOST timer).
2. LOCALIZING or LOST: localize the frame in the memory
   (:class:`robot.memory.localize.Localizer`), on every path that runs through the
   place; a localization plans the route to the goal and starts (or restarts) the
   follower. The route is the shortest from the key image found and from those of
   other paths that the junctions confirm are the same place
   (:func:`robot.memory.junctions.same_place`; a robot relocalized on a corridor that a
   loop runs along takes the loop, not the long way round). LOST, a localization counts only
   within ``MissionConfig.relocalize_radius_m`` of the key image the robot was heading
   for (it stood, or drove blind a metre at most: a key image farther away is a
   look-alike, a failed attempt). Found at the goal key image
   itself, the robot has arrived (a goal a few centimetres behind it on its path, which
   no route reaches, is where it stands). A goal the memory does not reach from there
   fails the mission (``no_route``).
3. FOLLOWING: one servo cycle, its command to the base; the estimator's LOST, each
   key image reached and the final key image switch go to the mission.
4. A ``Tick`` drives the give-up timers. A transition whose commands include STOP
   stops the base at once.

:meth:`MissionRun.run` cycles once per ``period_ns`` scheduled by deadline on the
clock (STYLE.md sec. 3) and ends in a final state, when the frame source ends
(``camera_ended``), or after ``max_duration_ns`` (``time_limit``); the base is
stopped on the way out.

Every transition, key image switch and localization attempt is an :class:`AppEvent`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.follower import FollowerConfig, FollowStep, RouteFollower
from robot.memory.junctions import same_place
from robot.memory.localize import Localization, Localizer
from robot.mission import (
    FINAL_STATES,
    Abort,
    Bumper,
    Command,
    KeyImageReached,
    LocalizationFailed,
    Localized,
    Mission,
    MissionInput,
    MissionState,
    NoRoute,
    Obstacle,
    Stall,
    Start,
    Tick,
    Transition,
    WayClear,
)
from robot.mission import Arrived as ArrivedInput
from robot.mission import Lost as LostInput
from shared.clock import Clock
from shared.interfaces import BaseState, FrameSource, MobileBase
from shared.memory import VisualMemory


@dataclass(frozen=True, slots=True)
class AppEvent:
    """Something that happened, for the report, telemetry and logs.

    Attributes:
        t_ns: when, ns, on the application's clock.
        kind: "transition", "key_image", "localization" or "lost".
        reason: a short code (a mission reason, a switch reason, "ok"/"failed").
        detail: one human line.
    """

    t_ns: int
    kind: str
    reason: str
    detail: str


@dataclass(frozen=True, eq=False)
class CycleRecord:
    """One loop cycle, for observers (plots, video, telemetry).

    Attributes:
        t_ns: the frame's time, ns.
        state: the mission state after the cycle.
        base: the base's state at the frame.
        follow: the servo cycle, when following.
        localization: the localization, when localizing.
        route: the planned route (key image ids), once planned.
        targets: the key images headed for along it, junction crossings merged
            (:attr:`robot.follower.RouteFollower.targets`; ``follow.target_index`` indexes
            these, not ``route``).
        compute_ns: processing time of the cycle (frame in to command out), ns of
            the stopwatch (wall time on any clock).
    """

    t_ns: int
    state: MissionState
    base: BaseState
    follow: FollowStep | None
    localization: Localization | None
    route: tuple[int, ...]
    compute_ns: int
    targets: tuple[int, ...] = ()

    @property
    def target_number(self) -> int | None:
        """Which of the :attr:`targets` is headed for, counted from 1 (the last, the goal, on
        the cycle that arrives); None when not following or the targets are not known."""
        if self.follow is None or not self.targets:
            return None
        return min(self.follow.target_index, len(self.targets) - 1) + 1

    @property
    def target_key(self) -> int | None:
        """The key image headed for (:attr:`target_number`); None as it is."""
        number = self.target_number
        return None if number is None else self.targets[number - 1]


@dataclass(frozen=True, eq=False)
class MissionResult:
    """How a mission ended.

    Attributes:
        state: the final mission state (or the state when the loop stopped).
        reason: the reason of the last transition.
        detail: its detail line.
        route: the last planned route (empty when never planned).
        key_images_reached: targets of the route reached (a junction crossing counts once).
        targets: targets of the route.
        events: everything that happened, in order.
    """

    state: MissionState
    reason: str
    detail: str
    route: tuple[int, ...]
    key_images_reached: int
    targets: int
    events: tuple[AppEvent, ...] = field(default_factory=tuple)

    @property
    def reached_goal(self) -> bool:
        """The goal key image was reached."""
        return self.state is MissionState.ARRIVED


class MissionRun:
    """One mission to a goal key image (see the module docstring).

    Args:
        memory: the visual memory.
        config: all component configs (features, localize, path state, estimator,
            switching, control, mission; the camera mount from ``config.camera.mount``).
        base: the mobile base.
        rng: draws the RANSAC samples.
        localizer: finds the robot in ``memory``; None builds one over all its key images.
        stopwatch: wall-time counter for ``compute_ns``, ns (default ``time.perf_counter_ns``).
    """

    def __init__(self, memory: VisualMemory, config: VmnavConfig, base: MobileBase,
                 rng: np.random.Generator, *, localizer: Localizer | None = None,
                 stopwatch: Callable[[], int] = time.perf_counter_ns) -> None:
        self._memory = memory
        self._config = config
        self._base = base
        self._rng = rng
        self._stopwatch = stopwatch
        self._localizer = (localizer if localizer is not None else
                           Localizer.from_memory(memory, config.camera.mount, config.features,
                                                 config.localize))
        self._follower_config = FollowerConfig(
            features=config.features, path_state=config.path_state,
            estimator=config.estimator, switching=config.switching, control=config.control,
            mount=config.camera.mount)
        self._mission = Mission(config.mission, config.safety)
        self._events: list[AppEvent] = []
        self._follower: RouteFollower | None = None
        self._route: tuple[int, ...] = ()
        self._last: Transition | None = None
        self._reached = 0
        self._lost_near: int | None = None  # LOST: the key image the robot was heading for

    @property
    def state(self) -> MissionState:
        """The mission's state now."""
        return self._mission.state

    @property
    def finished(self) -> bool:
        """The mission is in a final state."""
        return self._mission.state in FINAL_STATES

    @property
    def goal_id(self) -> int | None:
        """The goal key image; None before :meth:`start`."""
        return self._mission.goal_id

    @property
    def events(self) -> tuple[AppEvent, ...]:
        """Everything that happened so far, in order."""
        return tuple(self._events)

    @property
    def follower(self) -> RouteFollower | None:
        """The route follower of the route planned last; None before the first plan."""
        return self._follower

    def start(self, goal_id: int, t_ns: int) -> None:
        """Start the mission to ``goal_id`` at ``t_ns``: the next cycles localize.

        Raises:
            UnknownKeyframeError: ``goal_id`` is not in the memory (nothing changes).
        """
        self._memory.keyframe(goal_id)
        self._feed(Start(t_ns, goal_id))

    def abort(self, t_ns: int, cause: str, detail: str) -> None:
        """End an active mission for ``cause`` (one of :data:`robot.mission.ABORT_CAUSES`;
        the base stops)."""
        if not self.finished:
            self._feed(Abort(t_ns, cause, detail))

    def result(self) -> MissionResult:
        """How the mission ended (or stands)."""
        last = self._last
        return MissionResult(
            state=self._mission.state,
            reason="" if last is None else last.reason,
            detail="" if last is None else last.detail,
            route=self._route, key_images_reached=self._reached,
            targets=0 if self._follower is None else len(self._follower.targets),
            events=self.events)

    def run(self, goal_id: int, frames: FrameSource, clock: Clock, period_ns: int,
            max_duration_ns: int,
            observer: Callable[[CycleRecord], None] | None = None) -> MissionResult:
        """Run the mission to ``goal_id`` until it ends (see the module docstring).

        Args:
            goal_id: the goal key image.
            frames: the camera.
            clock: time and waiting.
            period_ns: the servo period, ns (the camera's frame period).
            max_duration_ns: give up (``time_limit``) after this long, ns.
            observer: called after every cycle.

        Raises:
            UnknownKeyframeError: ``goal_id`` is not in the memory (the robot never moved).
        """
        start_ns = clock.now_ns()
        self.start(goal_id, start_ns)
        deadline_ns = start_ns
        while not self.finished:
            if clock.now_ns() - start_ns >= max_duration_ns:
                self.abort(clock.now_ns(), "time_limit",
                           f"time limit {max_duration_ns / 1e9:.0f} s reached")
                break
            frame = frames.read()
            if frame is None:
                self.abort(clock.now_ns(), "camera_ended", "the camera ended")
                break
            record = self.cycle(*frame)
            if observer is not None:
                observer(record)
            deadline_ns += period_ns
            clock.sleep_until_ns(deadline_ns)
        self._base.stop()
        return self.result()

    def cycle(self, t_ns: int, image: npt.NDArray[np.uint8]) -> CycleRecord:
        """One cycle on the frame ``image`` ((H, W) uint8 grey) taken at ``t_ns`` (module
        rules); nothing happens in a final state but the record."""
        started = self._stopwatch()
        base = self._base.state()
        pushed = base.blocked is not None and base.blocked.cause == "pushed"
        if base.bumped and not pushed:  # pushed while standing: the robot waits (rule 1)
            self._feed(Bumper(t_ns))
        elif base.stalled:
            self._feed(Stall(t_ns))
        self._safety_hold(t_ns, base)
        follow: FollowStep | None = None
        localization: Localization | None = None
        state = self._mission.state
        if state in (MissionState.LOCALIZING, MissionState.LOST):
            localization = self._localize(t_ns, image, base)
        elif state is MissionState.FOLLOWING and self._follower is not None:
            follow = self._follow(t_ns, image, base, self._follower)
        if self._mission.state not in FINAL_STATES:
            self._feed(Tick(t_ns))
        return CycleRecord(t_ns=t_ns, state=self._mission.state, base=base,
                           follow=follow, localization=localization, route=self._route,
                           compute_ns=self._stopwatch() - started,
                           targets=() if self._follower is None else self._follower.targets)

    def _safety_hold(self, t_ns: int, base: BaseState) -> None:
        """Rule 1's wait and resume."""
        state, follower = self._mission.state, self._follower
        if base.blocked is not None and state is MissionState.FOLLOWING:
            self._feed(Obstacle(t_ns, base.blocked.describe()))
            if self._mission.state is MissionState.WAITING and follower is not None:
                follower.pause(t_ns)
        elif base.blocked is None and state is MissionState.WAITING:
            self._feed(WayClear(t_ns))
            if follower is not None:
                follower.resume(t_ns)

    def _localize(self, t_ns: int, image: npt.NDArray[np.uint8],
                  base: BaseState) -> Localization:
        found = self._localizer.localize(image, each_path=True)
        if not found.ok or found.keyframe_id is None:
            detail = f"best {found.detail}"
            self._events.append(AppEvent(t_ns, "localization", "failed", detail))
            self._feed(LocalizationFailed(t_ns, detail))
            return found
        assert found.ahead_id is not None  # set with keyframe_id
        # (nearest, first ahead: the route's first target) on each path through the place.
        places = [(found.keyframe_id, found.ahead_id)] + [
            (nearest, ahead) for nearest, ahead in found.elsewhere
            if same_place(self._memory, found.keyframe_id, nearest,
                          self._config.localize.max_yaw_deg)]
        radius_m = self._config.mission.relocalize_radius_m
        near = (None if self._lost_near is None
                else self._memory.within(self._lost_near, radius_m))
        if near is not None and not any(nearest in near for nearest, _ in places):
            detail = (f"{found.detail}: more than {radius_m:g} m from key image "
                      f"{self._lost_near}, where the robot was lost")
            self._events.append(AppEvent(t_ns, "localization", "too_far", detail))
            self._feed(LocalizationFailed(t_ns, detail))
            return found
        self._events.append(AppEvent(t_ns, "localization", "ok", found.detail))
        self._lost_near = None
        goal_id = self._mission.goal_id
        assert goal_id is not None  # set by Start
        if any(nearest == goal_id != ahead for nearest, ahead in places):  # just past the goal
            self._feed(ArrivedInput(t_ns, goal_id))
            return found
        route = self._memory.plan_route_from([ahead for _, ahead in places], goal_id)
        if not route:
            self._feed(NoRoute(t_ns, f"no route from key image {found.ahead_id} to "
                                     f"goal key image {goal_id} in the memory graph"))
            return found
        start = route[0]
        if start != found.ahead_id:
            self._events.append(AppEvent(
                t_ns, "localization", "same_place",
                f"key image {start} (path {self._memory.keyframe(start).path_id}) is where key "
                f"image {found.ahead_id} is, and the route from it is shorter"))
        self._route = tuple(route)
        self._follower = RouteFollower(self._memory, route, self._follower_config, self._rng,
                                       t_ns, base)
        self._reached = 0
        self._feed(Localized(t_ns, start, found.matches))
        return found

    def _follow(self, t_ns: int, image: npt.NDArray[np.uint8], base: BaseState,
                follower: RouteFollower) -> FollowStep:
        step = follower.step(t_ns, image, base)
        self._base.command(step.twist.v_m_s, step.twist.omega_rad_s)
        if step.switch is not None:
            switch = step.switch
            self._reached += 1
            key = follower.targets[switch.reached_index]
            self._events.append(AppEvent(
                t_ns, "key_image", switch.reason,
                f"reached key image {key} ({switch.reached_index + 1}/{len(follower.targets)})"))
            self._feed(ArrivedInput(t_ns, key) if switch.final else KeyImageReached(t_ns, key))
        if step.lost is not None:
            self._lost_near = self._route[min(self._reached, len(self._route) - 1)]
            self._events.append(AppEvent(t_ns, "lost", step.lost.reason, step.lost.message))
            self._feed(LostInput(t_ns, step.lost.message))
        return step

    def _feed(self, event: MissionInput) -> None:
        transition = self._mission.handle(event)
        if transition is None:
            return
        self._last = transition
        self._events.append(AppEvent(
            transition.t_ns, "transition", transition.reason,
            f"{transition.source.name} -> {transition.target.name}: {transition.detail}"))
        if Command.STOP in transition.commands:
            self._base.stop()


def start_run(memory: VisualMemory, config: VmnavConfig, base: MobileBase,
              rng: np.random.Generator, goal_id: int, t_ns: int, *,
              localizer: Localizer | None = None,
              stopwatch: Callable[[], int] = time.perf_counter_ns) -> MissionRun:
    """A mission run to ``goal_id`` started at ``t_ns``, built the one way both the robot
    (:class:`robot.goal_runs.GoalRuns`) and replay (:func:`robot.replay.replay`, from the
    logged config and generator state) build it, so a replayed run is the logged one.

    Args:
        memory: the visual memory.
        config: the run's settings (what the field log records with its start).
        base: the mobile base.
        rng: the run's own generator (RANSAC samples); its state before this call is
            what the field log records.
        goal_id: the goal key image.
        t_ns: the start time, ns.
        localizer: over ``memory`` with ``config``'s features and localize settings (the
            robot keeps one per memory); None builds it.
        stopwatch: wall-time counter for the cycles' ``compute_ns``, ns.

    Raises:
        UnknownKeyframeError: ``goal_id`` is not in the memory.
    """
    run = MissionRun(memory, config, base, rng, localizer=localizer, stopwatch=stopwatch)
    run.start(goal_id, t_ns)
    return run
