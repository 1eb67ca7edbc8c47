"""The robot's top-level machine: modes, arming, teaching, goal runs and failsafes (pure).

Theory of operation
-------------------

The robot is in one of four modes (ArduRover's HOLD, MANUAL, AUTO, GUIDED), armed or
not, and does one thing at a time (its :class:`Activity`): nothing in particular
(IDLE), a goal run (RUNNING: one :class:`~robot.mission_run.MissionRun` to a goal of
the uploaded mission in AUTO, or to a photo's key image in GUIDED), or recording a
path (TEACHING). Two conditions cut across: the base not reporting (``base_lost``)
and photos handed to the worker and not yet back (``photos_pending``). The robot
starts in HOLD, armed, IDLE.

An event (:mod:`robot.mode_events`) is an operator's request (queued by the link thread), a result
from the worker (a photo found or not, a path stored or not), or something the loop
saw (a run ended, the base going quiet or coming back, the GCS failsafe).
:func:`decide` looks the (activity, event) pair up in ``_TRANSITIONS`` and returns a
:class:`Decision`: the next :class:`TopState` and the :class:`Action` list the runtime
(:class:`robot.runtime.RobotRuntime`) carries out in order. What drives the base on
a frame follows from the state alone (:func:`drive_of`).

Rules (the table below is the whole behaviour):

1. Modes. HOLD: stopped. MANUAL: driven by the stick (MANUAL_CONTROL) until its
   dead-man. AUTO: the uploaded mission's goals in order, one run each; after the
   last goal, or when a run fails or aborts, the robot stops in HOLD. GUIDED: one
   run to the key image found from a photo, then HOLD; GUIDED without a run is
   stopped. Entering a mode drops the stick.
2. Leaving AUTO or GUIDED for another mode (or the GCS failsafe's "hold") ends the
   run as the operator's abort; AUTO again (a new ``StartGoals``) restarts from the
   current item.
3. Disarmed, the robot does not move in any mode; disarming ends a run; goals and
   photos are refused while disarmed (the link thread refuses them too; the table
   refuses what raced past it).
4. Teaching is refused during a run and enters MANUAL; goals and photos are refused
   while teaching. Stopping it (in any mode) stops the base and hands the key images
   to the worker, which stores the path; its result comes back as ``PathStored``
   (the runtime then works on the new memory) or ``PathNotStored``.
5. A photo goes to the worker to be found in the memory; ``PhotoFound`` ends the
   run in progress ("a new goal") and starts one to the key image in GUIDED;
   ``PhotoNotFound`` is a notice and nothing moves. A photo that comes back while
   teaching or disarmed is dropped with a notice.
6. A run that ends (``RunEnded``): arrived with goals left starts the next goal's
   run; otherwise the robot stops in HOLD. A goal gone from the memory when its run
   starts (``GoalGone``) also stops in HOLD.
7. The base not reporting (``BaseLost``): stopped in every mode, teaching skips
   frames; a run ends with ``hold`` (MissionConfig.base_lost_action "hold") or pauses
   ("continue") until ``BaseBack``.
8. The GCS failsafe (``GcsLost``): "stop" drops the stick, "hold" is rule 2's HOLD,
   "continue" changes nothing. A supervisor's ``TimeLimit`` ends a run in HOLD too,
   with its own cause; with no run it changes nothing.
9. An edge may carry a refusal: the state stays and the operator gets the line
   (WARNING). A pair missing from the table is a bug in the runtime and raises
   :class:`~shared.errors.IllegalEventError` (e.g. ``RunEnded`` with no run,
   ``TeachStop`` while a run drives, a photo result with none pending).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from robot.mode_events import (
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
from shared.errors import IllegalEventError
from shared.mavlink.modes import Mode


class Activity(enum.Enum):
    """What the robot works on."""

    IDLE = "idle"  #: no run, not teaching: HOLD and GUIDED stop, MANUAL drives by stick
    RUNNING = "running"  #: a goal run drives the robot (AUTO or GUIDED)
    TEACHING = "teaching"  #: key images are recorded while the operator drives


class Drive(enum.Enum):
    """What moves the base on a frame."""

    STOP = "stop"  #: zero velocity
    STICK = "stick"  #: the operator's MANUAL_CONTROL, scaled, until its dead-man
    RUN = "run"  #: the goal run's cycle


@dataclass(frozen=True, slots=True)
class TopState:
    """The robot's top-level state.

    Attributes:
        mode: the mode.
        armed: the motors accept commands.
        activity: what the robot works on.
        base_lost: the base does not report (rule 7).
        photos_pending: photos with the worker, not back yet.
    """

    mode: Mode = Mode.HOLD
    armed: bool = True
    activity: Activity = Activity.IDLE
    base_lost: bool = False
    photos_pending: int = 0


# ---------------------------------------------------------------------------
# Output.
# ---------------------------------------------------------------------------


class Action(enum.Enum):
    """What the runtime does for a decision, in the order given."""

    SAY = "say"  #: the decision's notice for the operator
    SAY_EVENT = "say_event"  #: the event's own line (a worker's result, a goal gone)
    SAY_BASE_BACK = "say_base_back"  #: notice the base reporting again, after how long
    END_RUN = "end_run"  #: abort the run (the decision's ``why``), keep its result, stop
    SAY_MODE = "say_mode"  #: notice "mode <NAME>" (dropped when the mode does not change)
    DROP_STICK = "drop_stick"  #: forget the last MANUAL_CONTROL
    START_GOALS = "start_goals"  #: the event's goals become the mission; run the first
    NEXT_GOAL = "next_goal"  #: run the mission's next goal
    START_PHOTO_GOAL = "start_photo_goal"  #: the found key image becomes the goal; run it
    FIND_PHOTO = "find_photo"  #: hand the photo to the worker
    START_TEACH = "start_teach"  #: start a key image selector
    SAVE_PATH = "save_path"  #: hand the key images to the worker to store the path
    ADOPT_MEMORY = "adopt_memory"  #: work on the memory the worker stored
    STOP = "stop"  #: stop the base now


@dataclass(frozen=True, slots=True)
class Decision:
    """What an event does.

    Attributes:
        state: the state after the event.
        actions: what the runtime does, in order.
        say: the line of :attr:`Action.SAY` (a refusal's too), WARNING.
        why: the reason a run ends (:attr:`Action.END_RUN`), for its detail line.
        cause: its cause code (one of :data:`robot.mission.ABORT_CAUSES`).
        refused: the event was refused (rule 9): only ``say`` comes of it.
    """

    state: TopState
    actions: tuple[Action, ...] = ()
    say: str = ""
    why: str = ""
    cause: str = ""
    refused: bool = False


# ---------------------------------------------------------------------------
# The transition table.
# ---------------------------------------------------------------------------


class _Guard(enum.Enum):
    ALWAYS = enum.auto()
    DISARMED = enum.auto()  #: the robot is disarmed
    NEW_MODE = enum.auto()  #: SetMode to another mode than the current one
    DISARMING = enum.auto()  #: Arm(False)
    HOLD_ON_LOSS = enum.auto()  #: BaseLost with hold
    NEXT_GOAL = enum.auto()  #: RunEnded with a goal left
    GCS_STOP = enum.auto()  #: GcsLost "stop"
    GCS_HOLD = enum.auto()  #: GcsLost "hold"


class _Asked(enum.Enum):
    MODE = "the mode SetMode asks for"


_KEEP = None  #: an edge's activity or mode that stays as it is
_ASKED = _Asked.MODE


@dataclass(frozen=True, slots=True)
class _Edge:
    guard: _Guard = _Guard.ALWAYS
    activity: Activity | None = _KEEP
    mode: Mode | _Asked | None = _KEEP
    actions: tuple[Action, ...] = ()
    say: str = ""
    refusal: bool = False


def _refuse(text: str, guard: _Guard = _Guard.ALWAYS) -> _Edge:
    """An edge that changes nothing and tells the operator ``text`` (rule 9)."""
    return _Edge(guard, actions=(Action.SAY,), say=text, refusal=True)


A = Action
_RUNNING, _IDLE, _TEACHING = Activity.RUNNING, Activity.IDLE, Activity.TEACHING

#: Entering a mode: the notice (when it changes) and the stick dropped (rule 1).
_MODE = (A.SAY_MODE, A.DROP_STICK)
#: The worker's results, whatever the robot is doing (rules 4, 5).
_WORKER: dict[type, tuple[_Edge, ...]] = {
    PhotoNotFound: (_Edge(actions=(A.SAY_EVENT,)),),
    PathStored: (_Edge(actions=(A.ADOPT_MEMORY, A.SAY_EVENT)),),
    PathNotStored: (_Edge(actions=(A.SAY_EVENT,)),),
}
#: The base failsafe (rule 7) where no run can end.
_BASE_QUIET: dict[type, tuple[_Edge, ...]] = {
    BaseLost: (_Edge(actions=(A.SAY,), say="base not reporting: stopped"),),
    BaseBack: (_Edge(actions=(A.SAY_BASE_BACK,)),),
}
#: The GCS failsafe (rule 8) where no run can end.
_GCS_QUIET: tuple[_Edge, ...] = (
    _Edge(_Guard.GCS_STOP, actions=(A.DROP_STICK,)),
    _Edge(_Guard.GCS_HOLD, mode=Mode.HOLD, actions=_MODE),
    _Edge(),  # "continue"
)

_TRANSITIONS: dict[Activity, dict[type, tuple[_Edge, ...]]] = {
    Activity.IDLE: {
        SetMode: (_Edge(mode=_ASKED, actions=_MODE),),
        Arm: (_Edge(),),
        StartGoals: (_refuse("mission refused: disarmed", _Guard.DISARMED),
                     _Edge(activity=_RUNNING, mode=Mode.AUTO, actions=(A.START_GOALS,))),
        GotoPhoto: (_refuse("photo goal refused: disarmed", _Guard.DISARMED),
                    _Edge(actions=(A.FIND_PHOTO,))),
        PhotoFound: (_refuse("photo goal dropped: disarmed", _Guard.DISARMED),
                     _Edge(activity=_RUNNING, mode=Mode.GUIDED,
                           actions=(A.SAY_EVENT, A.START_PHOTO_GOAL))),
        TeachStart: (_Edge(activity=_TEACHING, mode=Mode.MANUAL,
                           actions=(*_MODE, A.START_TEACH)),),
        TeachStop: (_refuse("teach stop refused: not teaching"),),
        GcsLost: _GCS_QUIET,
        TimeLimit: (_Edge(),),
        **_WORKER,
        **_BASE_QUIET,
    },
    Activity.RUNNING: {
        SetMode: (_Edge(_Guard.NEW_MODE, activity=_IDLE, mode=_ASKED,
                        actions=(A.END_RUN, *_MODE)),
                  _Edge(actions=(A.DROP_STICK,))),
        Arm: (_Edge(_Guard.DISARMING, activity=_IDLE, mode=Mode.HOLD, actions=(A.END_RUN,)),
              _Edge()),
        StartGoals: (_Edge(mode=Mode.AUTO, actions=(A.END_RUN, A.START_GOALS)),),
        GotoPhoto: (_Edge(actions=(A.FIND_PHOTO,)),),
        PhotoFound: (_Edge(mode=Mode.GUIDED,
                           actions=(A.SAY_EVENT, A.END_RUN, A.START_PHOTO_GOAL)),),
        TeachStart: (_refuse("teach start refused: a mission is running"),),
        TeachStop: (_refuse("teach stop refused: not teaching"),),
        RunEnded: (_Edge(_Guard.NEXT_GOAL, actions=(A.NEXT_GOAL,)),
                   _Edge(activity=_IDLE, mode=Mode.HOLD, actions=(A.STOP,))),
        GoalGone: (_Edge(activity=_IDLE, mode=Mode.HOLD, actions=(A.SAY_EVENT,)),),
        BaseLost: (_Edge(_Guard.HOLD_ON_LOSS, activity=_IDLE, mode=Mode.HOLD,
                         actions=(A.SAY, A.END_RUN),
                         say="base not reporting: stopped, mission held"),
                   _Edge(actions=(A.SAY,), say="base not reporting: stopped, mission paused")),
        BaseBack: (_Edge(actions=(A.SAY_BASE_BACK,)),),
        GcsLost: (_Edge(_Guard.GCS_STOP, actions=(A.DROP_STICK,)),
                  _Edge(_Guard.GCS_HOLD, activity=_IDLE, mode=Mode.HOLD,
                        actions=(A.END_RUN, *_MODE)),
                  _Edge()),
        TimeLimit: (_Edge(activity=_IDLE, mode=Mode.HOLD, actions=(A.END_RUN, *_MODE)),),
        **_WORKER,
    },
    Activity.TEACHING: {
        SetMode: (_Edge(mode=_ASKED, actions=_MODE),),
        Arm: (_Edge(),),
        StartGoals: (_refuse("mission refused: teaching"),),
        GotoPhoto: (_refuse("photo goal refused: teaching"),),
        PhotoFound: (_refuse("photo goal dropped: teaching"),),
        TeachStart: (_refuse("teach start refused: already teaching"),),
        TeachStop: (_Edge(activity=_IDLE, actions=(A.STOP, A.SAVE_PATH)),),
        GcsLost: _GCS_QUIET,
        TimeLimit: (_Edge(),),
        **_WORKER,
        **_BASE_QUIET,
    },
}

#: Events that take a photo back from the worker.
_PHOTO_RESULTS = (PhotoFound, PhotoNotFound)


def decide(state: TopState, event: Event) -> Decision:
    """The decision of the table for ``event`` in ``state`` (module rules).

    Raises:
        IllegalEventError: the table has no row for the event in the state's activity
            (a bug in the caller), or a photo result comes with no photo pending.
    """
    row = _TRANSITIONS[state.activity]
    if type(event) not in row or (isinstance(event, _PHOTO_RESULTS)
                                  and state.photos_pending == 0):
        raise IllegalEventError("robot", state.activity.name, type(event).__name__)
    edge = next(e for e in row[type(event)] if _holds(e.guard, state, event))
    photos = state.photos_pending - isinstance(event, _PHOTO_RESULTS)
    if isinstance(event, GotoPhoto) and not edge.refusal:
        photos += 1
    mode = state.mode
    if isinstance(edge.mode, Mode):
        mode = edge.mode
    elif edge.mode is _ASKED:
        assert isinstance(event, SetMode)
        mode = event.mode
    actions = tuple(a for a in edge.actions if a is not A.SAY_MODE or mode is not state.mode)
    next_state = TopState(
        mode=mode,
        armed=event.armed if isinstance(event, Arm) else state.armed,
        activity=edge.activity if edge.activity is not None else state.activity,
        base_lost=(True if isinstance(event, BaseLost)
                   else False if isinstance(event, BaseBack) else state.base_lost),
        photos_pending=photos)
    cause, why = _why(event, mode) if A.END_RUN in actions else ("", "")
    return Decision(next_state, actions, edge.say, why, cause, edge.refusal)


def drive_of(state: TopState) -> Drive:
    """What moves the base on a frame in ``state`` (rules 1, 3, 7)."""
    if state.base_lost or not state.armed:
        return Drive.STOP
    if state.activity is Activity.RUNNING:
        return Drive.RUN
    return Drive.STICK if state.mode is Mode.MANUAL else Drive.STOP


def _holds(guard: _Guard, state: TopState, event: Event) -> bool:
    match guard:
        case _Guard.ALWAYS:
            return True
        case _Guard.DISARMED:
            return not state.armed
        case _Guard.NEW_MODE:
            return isinstance(event, SetMode) and event.mode is not state.mode
        case _Guard.DISARMING:
            return isinstance(event, Arm) and not event.armed
        case _Guard.HOLD_ON_LOSS:
            return isinstance(event, BaseLost) and event.hold
        case _Guard.NEXT_GOAL:
            return isinstance(event, RunEnded) and event.next_goal
        case _Guard.GCS_STOP:
            return isinstance(event, GcsLost) and event.action == "stop"
        case _Guard.GCS_HOLD:
            return isinstance(event, GcsLost) and event.action == "hold"
    raise AssertionError(f"unknown guard {guard}")


def _why(event: Event, mode: Mode) -> tuple[str, str]:
    """Why a run ends: its cause code (:data:`robot.mission.ABORT_CAUSES`) and detail line."""
    match event:
        case SetMode():
            return "operator_abort", f"mode {mode.name}"
        case GcsLost():
            return "gcs_lost", f"ground heartbeat lost: mode {mode.name}"
        case Arm(emergency=True):
            return "e_stop", "emergency stop"
        case Arm():
            return "disarmed", "disarmed"
        case StartGoals():
            return "new_goal", "a new mission started"
        case PhotoFound():
            return "new_goal", "a new goal"
        case BaseLost():
            return "base_lost", "the base stopped reporting"
        case TimeLimit(text=text):
            return "time_limit", text
    raise AssertionError(f"no reason for ending a run on {event!r}")
