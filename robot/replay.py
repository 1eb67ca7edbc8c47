"""Replay: rerun logged mission cycles through :class:`robot.mission_run.MissionRun` and
compare what it computes with what the robot logged.

Pure: logged data in (:mod:`robot.logged_missions` reads it from a field log), a
:class:`ReplayReport` out; no files, no clock.

Theory of operation. A mission run is a function of the memory, its config, its
random generator's state, its start (goal, time) and, per cycle, of the frame's time,
the frame and the base's state: all of which :class:`robot.field_log.FieldLog` logs.
:func:`replay` rebuilds the run at each :class:`MissionStart` with
:func:`robot.mission_run.start_run`, as the robot's runtime built it (the logged config
unless one is given, a generator in the logged state), on a :class:`ReplayBase` that
reports each cycle's logged :class:`~shared.interfaces.BaseState` and records the
commands, feeds it the logged frames, and compares each cycle's :data:`FIELDS`:

* ``lateral_error_m``, ``angular_error_rad``, ``progress_m``: the filtered y, theta, s;
* ``matched_points``: matches of the frame (the localization's while localizing);
* ``cmd_linear_x_m_s``, ``cmd_angular_z_rad_s``: the command the base got (null on
  cycles that sent none);
* ``target_index``, ``switch_reason``: the key image headed for, and the switch the
  cycle completed;
* ``mission_state``: the state after the cycle (transitions).

Numbers differ when they are more than ``tolerance`` apart; anything else (null
against a number, strings) when not equal. A cycle the log cannot replay (no frame
or no base state logged, or before any mission start) is skipped and counted; a
cycle without its logged values is fed but not compared. The replay goes on after a
difference: the base's states come from the log, not from the replayed commands.
Only lossless (PNG) frames reproduce the estimates exactly; JPEG frames are counted
as approximate.

Replay reruns the mission runs alone, not the robot process (:mod:`robot.process`):
the rest of the process (modes, teaching, the ground link, the worker) reacts to
requests and timings of a link and threads that a log cannot give back, while a
mission run depends only on the logged inputs above. So the two share how a mission
run is built and started, not the process.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.field_log import servo_state
from robot.mission_run import CycleRecord, MissionRun, start_run
from shared.errors import InputError
from shared.interfaces import BaseState
from shared.memory import VisualMemory

#: The servo state's fields compared, by their ``vmnav.ServoState`` names.
SERVO_FIELDS = ("lateral_error_m", "angular_error_rad", "progress_m", "matched_points",
                "target_index", "switch_reason", "mission_state")
#: The command's fields compared, by their ``vmnav.Command`` names with a ``cmd_`` prefix.
COMMAND_FIELDS = ("cmd_linear_x_m_s", "cmd_angular_z_rad_s")
FIELDS = SERVO_FIELDS + COMMAND_FIELDS
"""Every field compared per cycle, in report order."""


@dataclass(frozen=True, eq=False)
class MissionStart:
    """A logged mission start.

    Attributes:
        t_ns: the start time given to ``MissionRun.start``, ns.
        goal_id: the goal key image.
        rng_state: the run's bit generator state (``rng.bit_generator.state``).
        config: the run's config.
    """

    t_ns: int
    goal_id: int
    rng_state: Mapping[str, Any]
    config: VmnavConfig


@dataclass(frozen=True, eq=False)
class LoggedCycle:
    """A logged mission cycle.

    Attributes:
        t_ns: the frame's time, ns.
        base: the base's state the cycle read; None when not logged.
        image: (H, W) uint8 grey frame; None when not logged.
        lossless: ``image`` is exactly the frame the robot used (PNG).
        logged: the :data:`FIELDS` as logged (:func:`logged_fields`); None when the
            servo state was not logged.
    """

    t_ns: int
    base: BaseState | None
    image: npt.NDArray[np.uint8] | None
    lossless: bool
    logged: Mapping[str, Any] | None


@dataclass(frozen=True, slots=True)
class Divergence:
    """Where a replay first differed from the log.

    Attributes:
        t_ns: the cycle's time, ns.
        mission: index of the mission in the log (0 first).
        cycle: index of the cycle within its mission (0 first).
        field: one of :data:`FIELDS`.
        logged, replayed: the two values.
    """

    t_ns: int
    mission: int
    cycle: int
    field: str
    logged: Any
    replayed: Any


@dataclass(frozen=True, slots=True)
class FieldReport:
    """One field over all compared cycles.

    Attributes:
        mismatches: cycles where it differed.
        max_abs_diff: the largest |logged - replayed| where both were numbers (0 when
            never both); differences of null against a number count only as mismatches.
    """

    mismatches: int
    max_abs_diff: float


@dataclass(frozen=True, eq=False)
class ReplayReport:
    """What a replay found.

    Attributes:
        missions: mission starts replayed.
        cycles: cycles compared.
        fed_only: cycles fed to the run but not compared (their servo state was not logged).
        skipped: cycles that could not be replayed (no frame or base state logged, or
            before any mission start).
        approximate: compared cycles whose frame was lossy (JPEG).
        tolerance: the numbers' tolerance used.
        fields: per field of :data:`FIELDS`.
        first: the first difference; None when identical.
    """

    missions: int
    cycles: int
    fed_only: int
    skipped: int
    approximate: int
    tolerance: float
    fields: dict[str, FieldReport]
    first: Divergence | None

    @property
    def identical(self) -> bool:
        """Every compared field agreed within the tolerance."""
        return self.first is None

    @property
    def exact(self) -> bool:
        """Every cycle was replayed on its lossless frame."""
        return self.approximate == 0 and self.skipped == 0

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the counts, per-field results and the first difference."""
        first = self.first
        return {
            "identical": self.identical, "exact": self.exact, "missions": self.missions,
            "cycles": self.cycles, "fed_only": self.fed_only, "skipped": self.skipped,
            "approximate": self.approximate, "tolerance": self.tolerance,
            "fields": {name: {"mismatches": f.mismatches, "max_abs_diff": f.max_abs_diff}
                       for name, f in self.fields.items()},
            "first_divergence": None if first is None else {
                "t_ns": first.t_ns, "mission": first.mission, "cycle": first.cycle,
                "field": first.field, "logged": first.logged, "replayed": first.replayed},
        }


class ReplayBase:
    """A :class:`shared.interfaces.MobileBase` that reports logged states and records the
    commands it gets.

    Attributes:
        commands: every ``(v_m_s, omega_rad_s)`` commanded, in order (``stop`` adds
            ``(0.0, 0.0)``).
    """

    def __init__(self) -> None:
        self._state: BaseState | None = None
        self._command: tuple[float, float] | None = None
        self.commands: list[tuple[float, float]] = []

    def report(self, state: BaseState) -> None:
        """The state :meth:`state` returns from now on; forgets the last command."""
        self._state, self._command = state, None

    def last_command(self) -> tuple[float, float] | None:
        """The last :meth:`command` since :meth:`report` (``stop`` is not one)."""
        return self._command

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Record a command, m/s and rad/s."""
        self._command = (v_m_s, omega_rad_s)
        self.commands.append(self._command)

    def stop(self) -> None:
        """Record a stop."""
        self.commands.append((0.0, 0.0))

    def state(self) -> BaseState:
        """The state last reported.

        Raises:
            RuntimeError: none was (a bug of the replay loop).
        """
        if self._state is None:
            raise RuntimeError("the base was asked for its state before any was logged")
        return self._state


def generator_from_state(state: Mapping[str, Any]) -> np.random.Generator:
    """A numpy generator whose bit generator is in ``state`` (``bit_generator.state``).

    Raises:
        InputError: ``state`` names no numpy bit generator or does not fit it.
    """
    name = state.get("bit_generator") if isinstance(state, Mapping) else None
    kind = getattr(np.random, name, None) if isinstance(name, str) else None
    if not (isinstance(kind, type) and issubclass(kind, np.random.BitGenerator)):
        raise InputError("rng_state", f"names no numpy bit generator: {name!r}")
    bit_generator = kind()
    try:
        bit_generator.state = dict(state)
    except (TypeError, ValueError, KeyError) as e:
        raise InputError("rng_state", f"is not a {name} state: {e}") from None
    return np.random.Generator(bit_generator)


def logged_fields(servo: Mapping[str, Any], command: Mapping[str, Any] | None) -> dict[str, Any]:
    """The :data:`FIELDS` of a logged ``vmnav.ServoState`` and ``vmnav.Command`` (None:
    no command that cycle); a field missing from the log is None."""
    fields = {name: servo.get(name) for name in SERVO_FIELDS}
    fields["cmd_linear_x_m_s"] = None if command is None else command.get("linear_x_m_s")
    fields["cmd_angular_z_rad_s"] = None if command is None else command.get("angular_z_rad_s")
    return fields


def replayed_fields(record: CycleRecord, command: tuple[float, float] | None) -> dict[str, Any]:
    """The :data:`FIELDS` of a replayed cycle and the command the base got (None: none)."""
    state = servo_state(record)
    fields = {name: state[name] for name in SERVO_FIELDS}
    fields["cmd_linear_x_m_s"] = None if command is None else command[0]
    fields["cmd_angular_z_rad_s"] = None if command is None else command[1]
    return fields


def differs(logged: Any, replayed: Any, tolerance: float) -> tuple[bool, float | None]:
    """Whether two values of a field differ, and |logged - replayed| when both are numbers.

    A replayed NaN equals a logged null: JSON has no NaN, the log writes null
    (:func:`shared.logs.messages.encode_json`).
    """
    if _number(logged) and _number(replayed):
        diff = abs(float(logged) - float(replayed))
        return not diff <= tolerance, diff
    if logged is None and _number(replayed) and math.isnan(replayed):
        return False, None
    return logged != replayed, None


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


@dataclass
class _Tally:
    mismatches: dict[str, int] = field(default_factory=lambda: dict.fromkeys(FIELDS, 0))
    max_abs: dict[str, float] = field(default_factory=lambda: dict.fromkeys(FIELDS, 0.0))
    first: Divergence | None = None


def replay(items: Iterable[MissionStart | LoggedCycle], memory: VisualMemory, *,
           config: VmnavConfig | None = None, tolerance: float = 0.0) -> ReplayReport:
    """Replay a log's missions and compare each cycle (see the module docstring).

    Args:
        items: the log's mission starts and cycles in the order they happened.
        memory: the visual memory the robot used.
        config: replay with this config instead of each mission's logged one (what a
            parameter change does); None: the logged ones.
        tolerance: numbers within this (absolute, their units) are equal; >= 0.

    Raises:
        InputError: a mission's goal is not in ``memory``, a frame is not of its
            camera's size, or a bad generator state.
    """
    if not tolerance >= 0:
        raise InputError("tolerance", f"must be >= 0, got {tolerance}")
    size = (memory.camera.height, memory.camera.width)
    tally = _Tally()
    run: MissionRun | None = None
    base = ReplayBase()
    missions = cycles = fed_only = skipped = approximate = in_mission = 0
    for item in items:
        if isinstance(item, MissionStart):
            if item.goal_id not in memory.keyframes:
                raise InputError("memory", f"has no key image {item.goal_id}, the goal of the "
                                 f"mission started at {item.t_ns / 1e9:.3f} s: replay needs "
                                 f"the memory the robot used")
            base = ReplayBase()
            run = start_run(memory, item.config if config is None else config, base,
                            generator_from_state(item.rng_state), item.goal_id, item.t_ns)
            missions, in_mission = missions + 1, 0
            continue
        if run is None or item.base is None or item.image is None:
            skipped += 1
            continue
        if item.image.shape != size:
            raise InputError(f"frame at {item.t_ns / 1e9:.3f} s",
                             f"is {item.image.shape[1]}x{item.image.shape[0]} px; the memory's "
                             f"camera takes {size[1]}x{size[0]} px")
        base.report(item.base)
        record = run.cycle(item.t_ns, item.image)
        if item.logged is None:
            fed_only += 1
        else:
            cycles += 1
            approximate += 0 if item.lossless else 1
            _compare(tally, item, replayed_fields(record, base.last_command()), tolerance,
                     missions - 1, in_mission)
        in_mission += 1
    return ReplayReport(
        missions=missions, cycles=cycles, fed_only=fed_only, skipped=skipped,
        approximate=approximate, tolerance=tolerance,
        fields={name: FieldReport(tally.mismatches[name], tally.max_abs[name])
                for name in FIELDS},
        first=tally.first)


def _compare(tally: _Tally, item: LoggedCycle, replayed: Mapping[str, Any], tolerance: float,
             mission: int, cycle: int) -> None:
    assert item.logged is not None
    for name in FIELDS:
        logged = item.logged[name]
        different, diff = differs(logged, replayed[name], tolerance)
        if diff is not None:
            tally.max_abs[name] = max(tally.max_abs[name], diff)
        if different:
            tally.mismatches[name] += 1
            if tally.first is None:
                tally.first = Divergence(item.t_ns, mission, cycle, name, logged,
                                         replayed[name])
