"""The robot's MAVLink parameters, each bound to a field of :class:`~robot.config.VmnavConfig`.

The robot builds its :class:`ParamTable` from the config it loaded (TOML values
become the defaults), applies the parameter file on top, and after every
:class:`~shared.mavlink.params.vehicle.ParamChanged` rebuilds its config with
:func:`config_with_params`, so a PARAM_SET changes what the robot uses. Only the
robot reads this table: a ground station learns the names and values over the
wire (PARAM_VALUE).

Units on the wire are SI like the config's, except durations: the config holds
integer ns, a parameter seconds (float32 cannot hold ns), applied at 1 ms
resolution. Choices travel as their index in the config's tuple of names.
"""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass
from typing import Any

from robot.config import BASE_LOST_ACTIONS, CONTROL_LAWS, VmnavConfig
from shared.config import GCS_LOST_ACTIONS
from shared.errors import ConfigError
from shared.mavlink.params.table import ParamSpec, ParamTable


class Kind(enum.Enum):
    """How a config field maps to a float parameter."""

    FLOAT = "float"  #: same value and unit
    INT = "int"  #: a whole number
    SECONDS = "seconds"  #: config ns <-> parameter s, 1 ms resolution
    CHOICE = "choice"  #: config string <-> its index in ``choices``


@dataclass(frozen=True, slots=True)
class ParamBinding:
    """A parameter bound to ``VmnavConfig.<section>.<field>``."""

    name: str
    section: str
    field: str
    min: float
    max: float
    description: str
    kind: Kind = Kind.FLOAT
    choices: tuple[str, ...] = ()

    def to_param(self, config_value: Any) -> float:
        """The parameter value for a config field value."""
        if self.kind is Kind.SECONDS:
            return config_value / 1e9
        if self.kind is Kind.CHOICE:
            return float(self.choices.index(config_value))
        return float(config_value)

    def to_config(self, value: float) -> Any:
        """The config field value for a (validated) parameter value."""
        if self.kind is Kind.SECONDS:
            return round(value * 1e3) * 1_000_000
        if self.kind is Kind.CHOICE:
            return self.choices[int(value)]
        if self.kind is Kind.INT:
            return int(value)
        return value

    def spec(self, config: VmnavConfig) -> ParamSpec:
        """The parameter's spec, its default taken from ``config``."""
        description = self.description
        if self.choices:
            description += " (" + ", ".join(f"{i} {c}" for i, c in enumerate(self.choices)) + ")"
        default = self.to_param(getattr(getattr(config, self.section), self.field))
        return ParamSpec(self.name, default, self.min, self.max, description,
                         integer=self.kind in (Kind.INT, Kind.CHOICE),
                         choices=self.choices)


#: Every robot parameter, in index order (append only: indexes must stay stable).
ROBOT_PARAMS: tuple[ParamBinding, ...] = (
    ParamBinding("CTL_SPEED", "control", "speed_m_s", 0.01, 1.0,
                 "Forward speed V while following a route, m/s"),
    ParamBinding("CTL_MAX_OMEGA", "control", "max_omega_rad_s", 0.01, 1.5,
                 "Bound on the turn rate |omega|, rad/s"),
    ParamBinding("CTL_POLE", "control", "double_pole", 0.01, 10.0,
                 "Double pole of the lateral loop, 1/s or 1/m (control.pole_domain)"),
    ParamBinding("CTL_LAW", "control", "law", 0, len(CONTROL_LAWS) - 1,
                 "Control law", Kind.CHOICE, CONTROL_LAWS),
    ParamBinding("SW_ERR_IMG_MAX", "switching", "err_image_max_px", 1.0, 200.0,
                 "Key image reached when errImageMax is below this, px"),
    ParamBinding("EST_LOST_TMO", "estimator", "lost_timeout_ns", 0.1, 60.0,
                 "No vision estimate for this long means LOST, s", Kind.SECONDS),
    ParamBinding("MIS_LOC_TMO", "mission", "localize_timeout_ns", 1.0, 600.0,
                 "Localizing this long without success fails the mission, s", Kind.SECONDS),
    ParamBinding("MIS_LOC_TRIES", "mission", "localize_attempts", 1, 100,
                 "Failed localizations in a row that fail the mission", Kind.INT),
    ParamBinding("MIS_RELOC_TMO", "mission", "relocalize_timeout_ns", 1.0, 600.0,
                 "LOST this long without relocalizing fails the mission, s", Kind.SECONDS),
    ParamBinding("MIS_RELOC_TRIES", "mission", "relocalize_attempts", 1, 100,
                 "Failed relocalizations in one LOST episode that fail the mission", Kind.INT),
    ParamBinding("MIS_RELOC_RAD", "mission", "relocalize_radius_m", 0.5, 100.0,
                 "LOST, relocalize only this near the key image the robot was heading for, m"),
    ParamBinding("FS_GCS_ACTION", "mavlink", "gcs_lost_action", 0, len(GCS_LOST_ACTIONS) - 1,
                 "What the robot does when the ground heartbeat stops", Kind.CHOICE,
                 GCS_LOST_ACTIONS),
    ParamBinding("FS_BASE_ACTION", "mission", "base_lost_action", 0, len(BASE_LOST_ACTIONS) - 1,
                 "What a mission does when the base stops reporting", Kind.CHOICE,
                 BASE_LOST_ACTIONS),
    ParamBinding("EST_LOST_DIST", "estimator", "lost_distance_m", 0.1, 10.0,
                 "Driving this far without a vision estimate means LOST, m"),
    ParamBinding("MIS_LOST_LIMIT", "mission", "lost_limit", 1, 100,
                 "LOST this many times without reaching a key image fails the mission",
                 Kind.INT),
    ParamBinding("SAFE_STOP_DIST", "safety", "stop_distance_m", 0.1, 3.0,
                 "Forward motion stops when an echo in the way is this close to the front, m"),
    ParamBinding("SAFE_SLOW_DIST", "safety", "slow_distance_m", 0.2, 5.0,
                 "Nearer echoes in the way slow the robot down, m (> SAFE_STOP_DIST)"),
    ParamBinding("SAFE_CLR_MARGIN", "safety", "clear_margin_m", 0.0, 1.0,
                 "Stopped, the way is clear beyond SAFE_STOP_DIST plus this, m"),
    ParamBinding("SAFE_CLR_DWELL", "safety", "clear_dwell_ns", 0.0, 30.0,
                 "...for this long before the robot resumes, s", Kind.SECONDS),
    ParamBinding("SAFE_SIDE_MARGIN", "safety", "side_margin_m", 0.0, 0.5,
                 "The swept corridor's margin on each side of the robot, m"),
    ParamBinding("SAFE_SIDE_STOP", "safety", "side_stop_margin_m", 0.0, 0.5,
                 "Echoes within this of the robot's sides stop it; farther out in the "
                 "corridor, if they cannot lie nearer, they only slow it, m "
                 "(<= SAFE_SIDE_MARGIN; equal: no creeping past)"),
    ParamBinding("SAFE_WAIT", "safety", "wait_ns", 1.0, 3600.0,
                 "A mission stopped by an obstacle waits this long, then holds, s",
                 Kind.SECONDS),
    ParamBinding("SAFE_APPR_TIME", "safety", "approach_horizon_ns", 0.0, 3.0,
                 "An echo coming at the robot counts where it will be this long on, s",
                 Kind.SECONDS),
)


def robot_param_table(config: VmnavConfig) -> ParamTable:
    """The robot's parameters with ``config``'s values as defaults.

    Raises:
        ConfigError: a config value lies outside its parameter's range (names it).
    """
    return ParamTable([binding.spec(config) for binding in ROBOT_PARAMS])


def param_problem(config: VmnavConfig, table: ParamTable, name: str,
                  value: float) -> str | None:
    """What setting ``name`` to the in-range ``value`` would break in the config with the
    other parameters as they are (e.g. ``safety: slow_distance_m must be > ...``); None
    when it fits."""
    trial = ParamTable([*table])
    for other, current in table.values().items():
        trial.set(other, current)
    trial.set(name, value)
    try:
        config_with_params(config, trial)
    except ConfigError as e:
        return e.problem
    return None


def config_with_params(config: VmnavConfig, table: ParamTable) -> VmnavConfig:
    """``config`` with every parameter that differs from its default applied.

    Parameters at their default leave the config field untouched (no rounding).

    Raises:
        ConfigError: the combination breaks a config rule (``"parameters: <section>:
            <problem>"``).
    """
    changes: dict[str, dict[str, Any]] = {}
    for binding in ROBOT_PARAMS:
        value = table.value(binding.name)
        if value != table.spec_of(binding.name).default:
            changes.setdefault(binding.section, {})[binding.field] = binding.to_config(value)
    sections: dict[str, Any] = {}
    for section, fields in changes.items():
        try:
            sections[section] = dataclasses.replace(getattr(config, section), **fields)
        except ValueError as e:
            raise ConfigError("parameters", f"{section}: {e}") from None
    return dataclasses.replace(config, **sections)
