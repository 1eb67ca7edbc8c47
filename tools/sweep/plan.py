"""A sweep's plan: the axes its cases run over, read from TOML and checked before any case runs.

A plan file (docs/sweeps.md; ``examples/sweeps/*.toml``)::

    [sweep]                          # optional: what every case shares
    routes = ["east_a", "east_b"]    # taught, in order [default: all the world's]
    goal = 17                        # the goal key image [default: the demo's]
    config = "vmnav.toml"            # the vmnav config file, relative to the plan
    max_omega_deg = 25.0             # the turn-rate bound, deg/s [default: the config's]

    [axes]                           # each a list of values; a case per combination
    world = ["lab", "campus"]        # built-in, or a world TOML file relative to the plan
    seed = {first = 1, count = 20}   # or a list: [1, 2, 5]
    people = [0, 3, 6]
    lighting = ["none", "lamps-off=0.5,hour=17"]   # as --lighting; "none": as taught
    moved = [0.0, 0.3]
    removed = ["none", "0.5"]        # as --removed
    doors = ["none", "door_a=closed"]              # as --doors
    calibration = ["default", "wide.json"]         # camera files, relative to the plan
    law = ["paper", "paper+ff"]
    speed_m_s = [0.2, 0.3]
    start_offset_m = [0.3]

An axis left out takes ``vmnav demo``'s default. A case is a ``vmnav demo`` command
line (:mod:`tools.harness.repeat_args`): its options say everything it depends on, its
id is a hash of them, and the same options rerun it alone.

Files (a world, a camera, the config) are taken relative to the plan and named in the
options relative to the working directory where they lie under it
(``docs/sweeps/lens1024.json`` from the project's root), so that a case's id, the plan
stored with its results and the commands that rerun its cases are the same in every clone
run from its root; the tasks are given them as absolute paths (:attr:`Case.run_argv`: a
Ray worker runs in a folder of its own).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from shared.errors import InputError

#: Every axis: its ``vmnav demo`` option and the kind of its values.
AXES: dict[str, tuple[str, type]] = {
    "world": ("--world", str),
    "seed": ("--seed", int),
    "people": ("--people", int),
    "lighting": ("--lighting", str),
    "moved": ("--moved", float),
    "removed": ("--removed", str),
    "doors": ("--doors", str),
    "calibration": ("--calibration", str),
    "law": ("--law", str),
    "speed_m_s": ("--speed", float),
    "start_offset_m": ("--start-offset", float),
}
#: The axes whose options set the taught memory (with the plan's routes and config).
MEMORY_AXES = ("world", "seed", "calibration")
#: A text axis's value meaning "the option left out" (the demo's default).
NO_VALUE = ("none", "default")
#: The keys of ``[sweep]``: name -> the kinds allowed.
_SWEEP_KEYS: dict[str, tuple[type, ...]] = {
    "routes": (list,), "goal": (int,), "config": (str,), "max_omega_deg": (int, float)}
#: Axes whose text values are files, taken relative to the plan.
_FILE_AXES = ("world", "calibration")


@dataclass(frozen=True)
class Case:
    """One case: the options of its ``vmnav demo`` command line (no outputs).

    Attributes:
        values: the value of every axis (None: the demo's default), in :data:`AXES` order.
        argv: the options.
        case_id: 12 hex digits of the options' SHA-256.
        memory_argv: the options the taught memory depends on (world, seed, camera,
            routes, config).
        memory_name: the memory's folder name, e.g. ``lab-seed3-1a2b3c4d``.
    """

    values: tuple[tuple[str, object], ...]
    argv: tuple[str, ...]
    case_id: str
    memory_argv: tuple[str, ...]
    memory_name: str

    @property
    def run_argv(self) -> tuple[str, ...]:
        """:attr:`argv` with its files as absolute paths (what a task is given)."""
        return _absolute_files(self.argv)

    @property
    def run_memory_argv(self) -> tuple[str, ...]:
        """:attr:`memory_argv` with its files as absolute paths."""
        return _absolute_files(self.memory_argv)


@dataclass(frozen=True)
class SweepPlan:
    """What to run (see the module docstring).

    Attributes:
        axes: (axis, values) of the axes given, in :data:`AXES` order; files resolved.
        routes: the routes taught (None: all the world's).
        goal_id: the goal key image (None: the demo's).
        config: the vmnav config file (None: the defaults).
        max_omega_deg: the turn-rate bound, deg/s (None: the config's).
        source: where the plan came from (messages name its entries).
    """

    axes: tuple[tuple[str, tuple[object, ...]], ...]
    routes: tuple[str, ...] | None = None
    goal_id: int | None = None
    config: str | None = None
    max_omega_deg: float | None = None
    source: str = "plan"

    def to_dict(self) -> dict[str, Any]:
        """The plan as JSON data (stored with the results; equal plans give equal data)."""
        return {"axes": {name: list(values) for name, values in self.axes},
                "routes": None if self.routes is None else list(self.routes),
                "goal": self.goal_id, "config": self.config,
                "max_omega_deg": self.max_omega_deg}

    def shared_argv(self) -> list[str]:
        """The options every case has (``[sweep]``)."""
        argv: list[str] = []
        if self.config is not None:
            argv += ["--config", self.config]
        if self.routes is not None:
            argv += ["--routes", ",".join(self.routes)]
        if self.goal_id is not None:
            argv += ["--goal", str(self.goal_id)]
        if self.max_omega_deg is not None:
            argv += ["--max-omega-deg", _text(self.max_omega_deg)]
        return argv

    def cases(self) -> list[Case]:
        """Every combination of the axes' values, the last axis varying fastest."""
        names = [name for name, _ in self.axes]
        shared = self.shared_argv()
        memory_shared = [a for a in _pairs(shared) if a[0] in ("--config", "--routes")]
        cases = []
        for combination in itertools.product(*(values for _, values in self.axes)):
            given = dict(zip(names, combination, strict=True))
            values = tuple((name, given.get(name)) for name in AXES)
            argv = list(shared)
            memory_argv = [item for pair in memory_shared for item in pair]
            for name, value in values:
                if value is None:
                    continue
                argv += [AXES[name][0], _text(value)]
                if name in MEMORY_AXES:
                    memory_argv += [AXES[name][0], _text(value)]
            world = Path(str(given.get("world", "lab"))).stem
            cases.append(Case(
                values=values, argv=tuple(argv), case_id=_digest(argv)[:12],
                memory_argv=tuple(memory_argv),
                memory_name=f"{world}-seed{given.get('seed', 'default')}-"
                            f"{_digest(memory_argv)[:8]}"))
        return cases


def read_plan(path: Path) -> SweepPlan:
    """Read a plan file (structure only; :func:`tools.sweep.plan_check.check_plan` checks
    the values against the worlds, files and options).

    Raises:
        InputError: the file does not read or is not TOML, an unknown table, key or
            axis, an empty axis, a value of the wrong kind (naming the entry).
    """
    try:
        data = tomllib.loads(path.read_text())
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(path, f"not TOML: {e}") from None
    return plan_from_data(data, path.parent, str(path))


def plan_from_data(data: dict[str, Any], folder: Path, source: str = "plan") -> SweepPlan:
    """The plan of a parsed plan file; relative files are taken from ``folder``.

    Raises:
        InputError: see :func:`read_plan`.
    """
    for table in data:
        if table not in ("sweep", "axes"):
            raise InputError(f"{source}: [{table}]", "unknown table (known: [sweep], [axes])")
    sweep = _table(data, "sweep", source)
    for key, value in sweep.items():
        where = f"{source}: [sweep] {key}"
        if key not in _SWEEP_KEYS:
            raise InputError(where, f"unknown key (known: {', '.join(_SWEEP_KEYS)})")
        if isinstance(value, bool) or not isinstance(value, _SWEEP_KEYS[key]):
            raise InputError(where, f"wrong kind of value {value!r}")
    routes = sweep.get("routes")
    if routes is not None and (not routes or not all(isinstance(r, str) for r in routes)):
        raise InputError(f"{source}: [sweep] routes", "must be a non-empty list of route names")
    axes_data = _table(data, "axes", source)
    for name in axes_data:
        if name not in AXES:
            raise InputError(f"{source}: [axes] {name}",
                             f"unknown axis (known: {', '.join(AXES)})")
    axes = tuple((name, _axis_values(name, axes_data[name], folder, source))
                 for name in AXES if name in axes_data)
    config = sweep.get("config")
    omega = sweep.get("max_omega_deg")
    return SweepPlan(axes=axes, routes=None if routes is None else tuple(routes),
                     goal_id=sweep.get("goal"),
                     config=None if config is None else _resolve(folder, config),
                     max_omega_deg=None if omega is None else float(omega), source=source)


def _table(data: dict[str, Any], name: str, source: str) -> dict[str, Any]:
    table = data.get(name, {})
    if not isinstance(table, dict):
        raise InputError(f"{source}: {name}", "must be a table")
    return table


def _axis_values(name: str, raw: object, folder: Path, source: str) -> tuple[object, ...]:
    """An axis's values: a list (``seed`` also ``{first, count}``), checked for kind."""
    where = f"{source}: [axes] {name}"
    if name == "seed" and isinstance(raw, dict):
        if set(raw) != {"first", "count"} or not all(
                isinstance(raw[k], int) and not isinstance(raw[k], bool) for k in raw):
            raise InputError(where, "a range is {first = N, count = M} with integers")
        raw = list(range(raw["first"], raw["first"] + raw["count"]))
    if not isinstance(raw, list):
        raise InputError(where, f"must be a list of values, got {raw!r}")
    if not raw:
        raise InputError(where, "is empty: give at least one value (or leave the axis out)")
    kind = AXES[name][1]
    values: list[object] = []
    for value in raw:
        if kind is str and isinstance(value, str) and value.strip():
            text = value.strip()
            values.append(None if text in NO_VALUE else
                          _resolve(folder, text) if name in _FILE_AXES and _is_file(text)
                          else text)
        elif kind is int and isinstance(value, int) and not isinstance(value, bool):
            values.append(value)
        elif (kind is float and isinstance(value, int | float) and not isinstance(value, bool)
              and math.isfinite(value)):
            values.append(float(value))
        else:
            raise InputError(where, f"{value!r} is not a {_KIND_NAMES[kind]}")
    if len(set(map(repr, values))) != len(values):
        raise InputError(where, "gives a value twice")
    return tuple(values)


_KIND_NAMES = {str: "non-empty text", int: "integer", float: "finite number"}


def _is_file(text: str) -> bool:
    """A world or camera value naming a file rather than a built-in world."""
    return text.endswith((".toml", ".json")) or "/" in text


def _resolve(folder: Path, text: str) -> str:
    """A file named in a plan in ``folder``, as options name it (module docstring)."""
    path = Path(text).expanduser()
    path = path if path.is_absolute() else (folder / path).resolve()
    try:
        return str(path.relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


#: The options whose values may be files (:data:`_FILE_AXES` and ``[sweep] config``).
_FILE_OPTIONS = frozenset({AXES[name][0] for name in _FILE_AXES} | {"--config"})


def _absolute_files(argv: tuple[str, ...]) -> tuple[str, ...]:
    """``argv`` with the values of :data:`_FILE_OPTIONS` that name files made absolute."""
    out = list(argv)
    for i in range(1, len(out), 2):
        if out[i - 1] in _FILE_OPTIONS and _is_file(out[i]):
            out[i] = str(Path(out[i]).resolve())
    return tuple(out)


def _text(value: object) -> str:
    """An option's text: integers without a decimal point, floats as repr."""
    return repr(value) if isinstance(value, float) else str(value)


def _pairs(argv: list[str]) -> list[tuple[str, str]]:
    return list(zip(argv[::2], argv[1::2], strict=True))


def _digest(argv: list[str]) -> str:
    return hashlib.sha256(json.dumps(argv).encode()).hexdigest()
