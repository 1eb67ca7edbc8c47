"""Declared parameters and their current values, as the parameter protocol exposes them.

Every parameter is a float on the wire (``MAV_PARAM_TYPE_REAL32``): MAVSDK and QGC
encode integer types bytewise for a generic autopilot while MAVProxy casts
(reference/mavlink-vehicle.md sec. 0.3), and a float reads the same under both.
Integer and choice parameters are floats with integral values, checked on set.
Names are ASCII, at most 16 characters (PARAM_VALUE.param_id); indexes follow
declaration order and never change while the table lives.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from shared.errors import ConfigError
from shared.mavlink.dialect import mavlink, to_float32

#: Longest parameter name (PARAM_VALUE.param_id is char[16]).
NAME_LEN = 16
#: The wire type of every parameter.
REAL32 = mavlink.MAV_PARAM_TYPE_REAL32


def param_id_from_name(name: str) -> bytes:
    """The ``param_id`` field carrying ``name``: ASCII, anything else as ``?``."""
    return name.encode("ascii", errors="replace")


@dataclass(frozen=True, slots=True)
class ParamSpec:
    """One declared parameter.

    ``integer`` parameters take whole numbers only; ``choices`` parameters are
    integers indexing the tuple (shown in the description).
    """

    name: str
    default: float
    min: float
    max: float
    description: str  #: one line with the unit, e.g. "Forward speed V, m/s"
    integer: bool = False
    choices: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not (0 < len(self.name) <= NAME_LEN and self.name.isascii()
                and self.name.isprintable() and " " not in self.name):
            raise ValueError(f"parameter name {self.name!r}: 1-{NAME_LEN} printable ASCII, "
                             f"no spaces")
        if self.choices:
            object.__setattr__(self, "integer", True)
            if (self.min, self.max) != (0, len(self.choices) - 1):
                raise ValueError(f"{self.name}: choices need min 0 and max {len(self.choices) - 1}")
        if not self.min <= self.max:
            raise ValueError(f"{self.name}: min {self.min} > max {self.max}")

    def problem(self, value: float) -> str | None:
        """Why ``value`` cannot be set, or None if it can.

        The bounds also admit their float32 roundings, so a bound sent over the wire
        (float32) is accepted.
        """
        if not math.isfinite(value):
            return f"{value} is not a finite number"
        low = min(self.min, to_float32(self.min))
        high = max(self.max, to_float32(self.max))
        if not low <= value <= high:
            return f"{value:g} is outside [{self.min:g}, {self.max:g}]"
        if self.integer and value != int(value):
            return f"{value:g} is not a whole number"
        return None


class ParamTable:
    """The vehicle's parameters: specs in a fixed order, and a current value for each.

    Args:
        specs: at least one parameter, names unique.

    Raises:
        ValueError: no specs, or duplicate names (a bug of the declaration).
        ConfigError: a default (from the config) that its own spec refuses.
    """

    def __init__(self, specs: Sequence[ParamSpec]) -> None:
        if not specs:
            raise ValueError("at least one parameter must be declared")
        self._specs = tuple(specs)
        self._index = {spec.name: i for i, spec in enumerate(self._specs)}
        if len(self._index) != len(self._specs):
            names = [s.name for s in self._specs]
            duplicate = next(n for n in names if names.count(n) > 1)
            raise ValueError(f"parameter {duplicate} is declared twice")
        for spec in self._specs:
            if (problem := spec.problem(spec.default)) is not None:
                raise ConfigError("parameters", f"{spec.name}: default {problem}")
        self._values = [spec.default for spec in self._specs]

    def __len__(self) -> int:
        return len(self._specs)

    def __iter__(self) -> Iterator[ParamSpec]:
        return iter(self._specs)

    def __contains__(self, name: object) -> bool:
        return name in self._index

    def index(self, name: str) -> int | None:
        """The index of ``name``, or None if no such parameter."""
        return self._index.get(name)

    def spec(self, index: int) -> ParamSpec:
        """The spec at ``index`` (0 .. len - 1)."""
        return self._specs[index]

    def spec_of(self, name: str) -> ParamSpec:
        """The spec of ``name`` (KeyError if undeclared)."""
        return self._specs[self._index[name]]

    def value(self, name: str) -> float:
        """The current value of ``name`` (KeyError if undeclared)."""
        return self._values[self._index[name]]

    def value_at(self, index: int) -> float:
        """The current value at ``index``."""
        return self._values[index]

    def values(self) -> dict[str, float]:
        """Every current value by name, in index order."""
        return {spec.name: v for spec, v in zip(self._specs, self._values, strict=True)}

    def problem(self, name: str, value: float) -> str | None:
        """Why ``name`` cannot take ``value`` (without the name), or None if it can."""
        i = self._index.get(name)
        if i is None:
            return "no such parameter"
        return self._specs[i].problem(value)

    def set(self, name: str, value: float) -> None:
        """Set ``name`` to ``value``.

        Raises:
            ConfigError: ``"param <name>: <problem>"`` for an unknown name or a value
                out of range (callers on the wire check :meth:`problem` first).
        """
        if (problem := self.problem(name, value)) is not None:
            raise ConfigError(f"param {name}", problem)
        self._values[self._index[name]] = float(value)
