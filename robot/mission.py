"""The mission state machine: localize, follow the route, arrive; or get lost, wait, or stop.

Theory of operation
-------------------

A mission starts IDLE. ``Start(goal)`` asks the application to localize the
robot in the visual memory (LOCALIZING); ``Localized(key image)`` lets it plan
the route and follow it (FOLLOWING) until ``Arrived`` (ARRIVED). No route from
there to the goal (``NoRoute``) fails the mission. While following, the estimator
may report ``Lost`` (no usable vision for too long, or too far): the robot stops
and relocalizes (LOST); ``Localized`` there continues the mission from the key image
found (back to FOLLOWING, reason "relocalized"). Localization that keeps failing
gives up: after ``*_attempts`` ``LocalizationFailed`` inputs in a row, or after
``*_timeout_ns`` in the state (checked on ``Tick``), the mission FAILED; so does a
robot lost ``lost_limit`` times without reaching a key image in between (each
relocalization led nowhere). The safety layer's hold (``Obstacle``: something in
the way) makes a following robot stop and wait (WAITING) with its route and its
estimate kept; ``WayClear`` resumes the route where it stopped; waiting
``SafetyConfig.wait_ns`` gives up (ABORTED, "blocked"). The bumper, a stall or an
``Abort`` (the operator, a failsafe, the loop's limits, each with its own cause)
end any active mission (ABORTED).

ARRIVED, ABORTED and FAILED are final: a new mission is a new :class:`Mission`.
FAILED is kept apart from ABORTED: ABORTED means something outside stopped the
robot (a person, an obstacle, the operator); FAILED means the method could not go on.
Every end carries its true cause as its reason (``REASONS``).

Rules:

1. Every input carries its time ``t_ns``; times never go backwards.
2. One input makes at most one :class:`Transition`. Every transition carries a
   reason code (``REASONS``), a one-line detail and the commands for the
   application, and is meant for telemetry and logs.
3. Commands belong to the state entered: entering LOCALIZING or LOST gives
   (STOP, LOCALIZE), FOLLOWING gives (FOLLOW,), WAITING and a final state give
   (STOP,). The application keeps doing what the state says until the next transition.
4. ``_TRANSITIONS`` below is the whole behaviour. An input listed as ``_IGNORED``
   in a state changes nothing (a safety input when nothing moves, a late ``Lost``
   from the estimator once the robot stopped following, a ``Tick`` without a
   timer). An input missing from a state's row is a bug in the caller and raises
   :class:`IllegalEventError` naming the input and the state: ``Start`` outside
   IDLE, ``Localized`` or ``LocalizationFailed`` when not localizing, ``Arrived``
   when not following, anything but safety inputs, ``Lost`` and ``Tick`` in a
   final state.
5. Guarded edges: ``_Guard.ATTEMPTS`` fires on the n-th failure in a row in the
   state (the count restarts on entering it); ``_Guard.TIMEOUT`` fires on the
   first ``Tick`` at or after the state's time limit from its entry;
   ``_Guard.LOST_LIMIT`` turns the ``lost_limit``-th ``Lost`` since the last
   ``KeyImageReached`` (accepted in every state, never a transition) into a failure
   (``lost_repeatedly``). An ``Abort`` edge takes its reason from the input's cause.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from robot.config import MissionConfig, SafetyConfig
from shared.errors import IllegalEventError


class MissionState(enum.Enum):
    """States of a mission."""

    IDLE = "idle"  #: no mission yet
    LOCALIZING = "localizing"  #: stopped; finding the start key image in the memory
    FOLLOWING = "following"  #: servoing along the route
    LOST = "lost"  #: stopped; relocalizing after the estimator lost the state
    WAITING = "waiting"  #: stopped for an obstacle; the route resumes when the way clears
    ARRIVED = "arrived"  #: final: the goal key image was reached
    ABORTED = "aborted"  #: final: stopped by the bumper, a stall, an obstacle or an abort
    FAILED = "failed"  #: final: localization, relocalization or route planning gave up


#: States no input leaves.
FINAL_STATES = frozenset({MissionState.ARRIVED, MissionState.ABORTED, MissionState.FAILED})


class Command(enum.Enum):
    """What the application must do on entering a state."""

    STOP = "stop"  #: command zero velocity to the base
    LOCALIZE = "localize"  #: run localization in the memory on the next frames
    FOLLOW = "follow"  #: plan the route from the localized key image and servo along it


# ---------------------------------------------------------------------------
# Inputs.
# ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Start:
    """The operator asks for a mission to the goal key image."""

    t_ns: int
    goal_id: int


@dataclass(frozen=True, slots=True)
class Localized:
    """Localization (or relocalization) found the robot at a key image."""

    t_ns: int
    keyframe_id: int
    matches: int


@dataclass(frozen=True, slots=True)
class LocalizationFailed:
    """One localization attempt failed (e.g. too few matches)."""

    t_ns: int
    reason: str


@dataclass(frozen=True, slots=True)
class Lost:
    """The estimator lost the state (:class:`robot.estimator.EstimatorLost`)."""

    t_ns: int
    reason: str


@dataclass(frozen=True, slots=True)
class Arrived:
    """The goal key image was reached (the final :class:`robot.switching.KeyImageSwitch`),
    or a localization found the robot at the goal key image itself."""

    t_ns: int
    keyframe_id: int


@dataclass(frozen=True, slots=True)
class Bumper:
    """A bumper was pressed."""

    t_ns: int


@dataclass(frozen=True, slots=True)
class Stall:
    """The base reports its motors stalled."""

    t_ns: int


#: Causes of :class:`Abort`: the operator (a mode change), disarming, the emergency
#: stop, a new goal replacing the mission, the ground's heartbeat lost (failsafe), the
#: base not reporting ("hold"), the loop's time limit, the camera ending, the robot
#: process closing.
ABORT_CAUSES = ("operator_abort", "disarmed", "e_stop", "new_goal", "gcs_lost", "base_lost",
                "time_limit", "camera_ended", "shutdown")


@dataclass(frozen=True, slots=True)
class Abort:
    """Something outside the mission ends it; ``cause`` is one of :data:`ABORT_CAUSES`."""

    t_ns: int
    cause: str = "operator_abort"
    detail: str = "operator abort"

    def __post_init__(self) -> None:
        if self.cause not in ABORT_CAUSES:
            raise ValueError(f"Abort: cause must be one of {', '.join(ABORT_CAUSES)}, "
                             f"got {self.cause!r}")


@dataclass(frozen=True, slots=True)
class NoRoute:
    """The memory graph has no route from the key image found to the goal."""

    t_ns: int
    detail: str


@dataclass(frozen=True, slots=True)
class KeyImageReached:
    """The follower reached a key image of the route (progress: the lost count restarts)."""

    t_ns: int
    keyframe_id: int


@dataclass(frozen=True, slots=True)
class Obstacle:
    """The safety layer holds the robot (``shared.interfaces.Blocked``, described)."""

    t_ns: int
    detail: str


@dataclass(frozen=True, slots=True)
class WayClear:
    """The safety layer's hold ended."""

    t_ns: int


@dataclass(frozen=True, slots=True)
class Tick:
    """Time passes; drives the give-up timers."""

    t_ns: int


MissionInput = (Start | Localized | LocalizationFailed | Lost | Arrived | Bumper | Stall
                | Abort | NoRoute | KeyImageReached | Obstacle | WayClear | Tick)


# ---------------------------------------------------------------------------
# Output.
# ---------------------------------------------------------------------------

#: Reason codes of transitions.
REASONS = ("start", "localized", "relocalized", "lost", "arrived", "localization_failed",
           "localization_timeout", "relocalization_failed", "relocalization_timeout",
           "lost_repeatedly", "no_route", "obstacle", "resumed", "blocked", "bumper", "stall",
           *ABORT_CAUSES)


@dataclass(frozen=True, slots=True)
class Transition:
    """A change of state, for the application, telemetry and logs.

    Attributes:
        t_ns: time of the input that caused it, ns.
        source: the state left.
        target: the state entered.
        reason: one of ``REASONS``.
        detail: one human line with the values behind the reason.
        cause: the input that caused it.
        commands: what the application must do now (rule 3).
    """

    t_ns: int
    source: MissionState
    target: MissionState
    reason: str
    detail: str
    cause: MissionInput
    commands: tuple[Command, ...]


# ---------------------------------------------------------------------------
# The transition table.
# ---------------------------------------------------------------------------


class _Guard(enum.Enum):
    NONE = enum.auto()
    ATTEMPTS = enum.auto()
    TIMEOUT = enum.auto()
    LOST_LIMIT = enum.auto()


@dataclass(frozen=True, slots=True)
class _Edge:
    target: MissionState
    reason: str  #: the reason code; ``_CAUSE``: the input's own cause (``Abort``)
    guard: _Guard = _Guard.NONE


_IGNORED = None
_CAUSE = "<the input's cause>"

_SAFETY: dict[type, _Edge | None] = {
    Bumper: _Edge(MissionState.ABORTED, "bumper"),
    Stall: _Edge(MissionState.ABORTED, "stall"),
    Abort: _Edge(MissionState.ABORTED, _CAUSE),
    Obstacle: _IGNORED, WayClear: _IGNORED, KeyImageReached: _IGNORED,
}
_QUIET: dict[type, _Edge | None] = {
    Bumper: _IGNORED, Stall: _IGNORED, Abort: _IGNORED, Lost: _IGNORED, Tick: _IGNORED,
    Obstacle: _IGNORED, WayClear: _IGNORED, KeyImageReached: _IGNORED,
}

_TRANSITIONS: dict[MissionState, dict[type, _Edge | None]] = {
    MissionState.IDLE: {
        Start: _Edge(MissionState.LOCALIZING, "start"),
        **_QUIET,
    },
    MissionState.LOCALIZING: {
        Localized: _Edge(MissionState.FOLLOWING, "localized"),
        Arrived: _Edge(MissionState.ARRIVED, "arrived"),
        NoRoute: _Edge(MissionState.FAILED, "no_route"),
        LocalizationFailed: _Edge(MissionState.FAILED, "localization_failed", _Guard.ATTEMPTS),
        Tick: _Edge(MissionState.FAILED, "localization_timeout", _Guard.TIMEOUT),
        Lost: _IGNORED,
        **_SAFETY,
    },
    MissionState.FOLLOWING: {
        Lost: _Edge(MissionState.LOST, "lost", _Guard.LOST_LIMIT),
        Arrived: _Edge(MissionState.ARRIVED, "arrived"),
        Tick: _IGNORED,
        **_SAFETY,
        Obstacle: _Edge(MissionState.WAITING, "obstacle"),
    },
    MissionState.WAITING: {
        **_SAFETY,
        WayClear: _Edge(MissionState.FOLLOWING, "resumed"),
        Tick: _Edge(MissionState.ABORTED, "blocked", _Guard.TIMEOUT),
        Lost: _IGNORED,
    },
    MissionState.LOST: {
        Localized: _Edge(MissionState.FOLLOWING, "relocalized"),
        Arrived: _Edge(MissionState.ARRIVED, "arrived"),
        NoRoute: _Edge(MissionState.FAILED, "no_route"),
        LocalizationFailed: _Edge(MissionState.FAILED, "relocalization_failed", _Guard.ATTEMPTS),
        Tick: _Edge(MissionState.FAILED, "relocalization_timeout", _Guard.TIMEOUT),
        Lost: _IGNORED,
        **_SAFETY,
    },
    MissionState.ARRIVED: dict(_QUIET),
    MissionState.ABORTED: dict(_QUIET),
    MissionState.FAILED: dict(_QUIET),
}

_ENTRY_COMMANDS: dict[MissionState, tuple[Command, ...]] = {
    MissionState.LOCALIZING: (Command.STOP, Command.LOCALIZE),
    MissionState.FOLLOWING: (Command.FOLLOW,),
    MissionState.LOST: (Command.STOP, Command.LOCALIZE),
    MissionState.WAITING: (Command.STOP,),
    MissionState.ARRIVED: (Command.STOP,),
    MissionState.ABORTED: (Command.STOP,),
    MissionState.FAILED: (Command.STOP,),
}


class Mission:
    """One mission's state machine (pure: inputs in, transitions out).

    Args:
        config: give-up limits.
        safety: the safety layer's settings (how long WAITING lasts).
    """

    def __init__(self, config: MissionConfig, safety: SafetyConfig | None = None) -> None:
        self._config = config
        self._wait_ns = (safety if safety is not None else SafetyConfig()).wait_ns
        self._lost_since_progress = 0
        self._state = MissionState.IDLE
        self._goal_id: int | None = None
        self._entered_ns = 0
        self._failures = 0
        self._last_ns: int | None = None

    @property
    def state(self) -> MissionState:
        """The current state."""
        return self._state

    @property
    def goal_id(self) -> int | None:
        """The goal key image, once started."""
        return self._goal_id

    def handle(self, event: MissionInput) -> Transition | None:
        """Feed one input.

        Args:
            event: the input.

        Returns:
            The transition it caused, or None (ignored, or a guard not yet met).

        Raises:
            IllegalEventError: the table forbids this input in the current state.
            ValueError: the input's time is earlier than the previous input's.
        """
        if self._last_ns is not None and event.t_ns < self._last_ns:
            raise ValueError(f"mission input {type(event).__name__} at {event.t_ns} ns is "
                             f"earlier than the previous input at {self._last_ns} ns")
        self._last_ns = event.t_ns
        row = _TRANSITIONS[self._state]
        if type(event) not in row:
            raise IllegalEventError("mission", self._state.name, type(event).__name__)
        if isinstance(event, KeyImageReached):  # progress: counted, never a transition
            self._lost_since_progress = 0
            return None
        edge = row[type(event)]
        if edge is _IGNORED:
            return None
        detail = self._guard_detail(edge, event)
        if detail is None:
            return None
        if isinstance(event, Start):
            self._goal_id = event.goal_id
        target, reason = edge.target, edge.reason
        if isinstance(event, Abort):
            reason = event.cause
        elif edge.guard is _Guard.LOST_LIMIT and self._lost_since_progress >= (
                self._config.lost_limit):
            target, reason = MissionState.FAILED, "lost_repeatedly"
        transition = Transition(t_ns=event.t_ns, source=self._state, target=target,
                                reason=reason, detail=detail, cause=event,
                                commands=_ENTRY_COMMANDS[target])
        self._state = target
        self._entered_ns = event.t_ns
        self._failures = 0
        return transition

    def _limits(self) -> tuple[int, int]:
        """(attempts, timeout_ns) of the current state's give-up guards."""
        cfg = self._config
        if self._state is MissionState.LOCALIZING:
            return cfg.localize_attempts, cfg.localize_timeout_ns
        if self._state is MissionState.WAITING:
            return 0, self._wait_ns
        return cfg.relocalize_attempts, cfg.relocalize_timeout_ns

    def _guard_detail(self, edge: _Edge, event: MissionInput) -> str | None:
        """The transition's detail line, or None when its guard does not fire yet."""
        if edge.guard is _Guard.ATTEMPTS:
            assert isinstance(event, LocalizationFailed)
            self._failures += 1
            attempts, _ = self._limits()
            if self._failures < attempts:
                return None
            return f"{self._failures} failed attempts in a row (limit {attempts}): {event.reason}"
        if edge.guard is _Guard.TIMEOUT:
            _, timeout_ns = self._limits()
            waited_ns = event.t_ns - self._entered_ns
            if waited_ns < timeout_ns:
                return None
            if self._state is MissionState.WAITING:
                return f"blocked for {waited_ns / 1e9:.1f} s: holding"
            return (f"{self._state.value} for {waited_ns / 1e9:.1f} s "
                    f"(limit {timeout_ns / 1e9:.1f} s)")
        if edge.guard is _Guard.LOST_LIMIT:
            assert isinstance(event, Lost)
            self._lost_since_progress += 1
            if self._lost_since_progress >= self._config.lost_limit:
                return (f"lost {self._lost_since_progress} times without reaching a key image "
                        f"(limit {self._config.lost_limit}): {event.reason}")
        if isinstance(event, WayClear):
            return f"way clear after {(event.t_ns - self._entered_ns) / 1e9:.1f} s: resuming"
        return _describe(event)


def _describe(event: MissionInput) -> str:
    match event:
        case Start(goal_id=goal):
            return f"to goal key image {goal}"
        case Localized(keyframe_id=kf, matches=n):
            return f"at key image {kf} ({n} matches)"
        case Lost(reason=reason):
            return reason
        case Abort(detail=detail) | NoRoute(detail=detail):
            return detail
        case Obstacle(detail=detail):
            return f"{detail}: waiting"
        case Arrived(keyframe_id=kf):
            return f"at goal key image {kf}"
        case Bumper():
            return "bumper pressed"
        case Stall():
            return "motors stalled"
    raise AssertionError(f"no description for {event!r}")  # the table has no other edges
