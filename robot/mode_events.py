"""The events of the robot's top-level machine (:mod:`robot.modes`): requests, the
worker's results and what the loop sees."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

from robot.memory.localize import Localizer
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory import VisualMemory


@dataclass(frozen=True, slots=True)
class SetMode:
    """The operator sets a mode (AUTO comes as :class:`StartGoals`)."""

    mode: Mode


@dataclass(frozen=True, slots=True)
class Arm:
    """The operator arms (True) or disarms the motors; ``emergency``: a forced disarm,
    the emergency stop (the base was stopped on receipt, ``robot.safe_base``)."""

    armed: bool
    emergency: bool = False


@dataclass(frozen=True, slots=True)
class StartGoals:
    """The operator starts the uploaded mission: ``goals[0]`` is item ``first_seq``."""

    goals: tuple[Goal, ...]
    first_seq: int


@dataclass(frozen=True, slots=True)
class GotoPhoto:
    """The operator asks to go where the photo at ``path`` was taken."""

    path: Path


@dataclass(frozen=True, slots=True)
class PhotoFound:
    """The worker found a photo at key image ``goal_key``; ``text`` for the operator."""

    goal_key: int
    text: str
    level: int = logging.INFO


@dataclass(frozen=True, slots=True)
class PhotoNotFound:
    """The worker did not find a photo (or could not read it); ``text`` says why."""

    level: int
    text: str


@dataclass(frozen=True, slots=True)
class TeachStart:
    """The operator starts recording a path called ``name``."""

    name: str


@dataclass(frozen=True, slots=True)
class TeachStop:
    """The operator stops recording."""


@dataclass(frozen=True, slots=True, eq=False)
class PathStored:
    """The worker wrote the taught path into ``memory`` (whole, never changed after);
    ``localizer`` is over it; ``text`` for the operator."""

    memory: VisualMemory
    localizer: Localizer
    path_id: int
    text: str
    level: int = logging.INFO


@dataclass(frozen=True, slots=True)
class PathNotStored:
    """The taught path was not stored (too short, or the memory not writable)."""

    text: str
    level: int = logging.ERROR


@dataclass(frozen=True, slots=True)
class RunEnded:
    """The goal run ended; ``next_goal``: it arrived and the mission has goals left."""

    next_goal: bool


@dataclass(frozen=True, slots=True)
class GoalGone:
    """The run's goal left the memory since the goals were checked; ``text`` says so."""

    text: str
    level: int = logging.ERROR


@dataclass(frozen=True, slots=True)
class BaseLost:
    """The base stopped reporting; ``hold``: the run ends (else it pauses)."""

    hold: bool


@dataclass(frozen=True, slots=True)
class BaseBack:
    """The base reports again."""


@dataclass(frozen=True, slots=True)
class GcsLost:
    """The ground heartbeat stopped; ``action`` as configured ("stop", "hold", "continue")."""

    action: str


@dataclass(frozen=True, slots=True)
class TimeLimit:
    """A supervisor's time limit for the run (a benchmark's, a test rig's) ran out; ``text``
    says which."""

    text: str


Event = (SetMode | Arm | StartGoals | GotoPhoto | PhotoFound | PhotoNotFound | TeachStart
         | TeachStop | PathStored | PathNotStored | RunEnded | GoalGone | BaseLost | BaseBack
         | GcsLost | TimeLimit)

#: Events that bring their own line for the operator (``text`` at ``level``).
TOLD = (PhotoFound, PhotoNotFound, PathStored, PathNotStored, GoalGone)
