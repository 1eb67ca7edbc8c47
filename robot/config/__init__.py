"""The robot application's config: one table per component, loaded from a vmnav TOML file.

The robot's tables sit at the top level of the file; the simulator's table
(``[sim]``, :data:`shared.config.SIM_TABLE`) is :mod:`sim.config`'s and left alone
here, so ``vmnav robot --config F`` and ``vmnav demo --config F`` read the same file::

    [control]
    speed_m_s = 0.25

    [camera]
    source = "http://robot.local:8080/stream.mjpg"

    [camera.mount]
    pitch_deg = -5.0

The camera mount belongs to the robot (``[camera.mount]``); files and field logs
written before it left the simulator's table had it in ``[sim.camera]``: a file
that still does is refused (:func:`load_config`), a logged config is read either way
(:func:`config_from_log`).

The component configs live by theme in :mod:`robot.config.vision`,
:mod:`robot.config.driving` and :mod:`robot.config.devices`; import them from here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from robot.config.devices import (
    CameraSourceConfig,
    FoxgloveConfig,
    PioneerDriverConfig,
    VideoConfig,
)
from robot.config.driving import (
    BASE_LOST_ACTIONS,
    CONTROL_LAWS,
    POLE_DOMAINS,
    ControlConfig,
    EstimatorConfig,
    MissionConfig,
    SafetyConfig,
    SwitchingConfig,
    TeleopConfig,
)
from robot.config.vision import (
    FRONT_END_METHODS,
    RELATIVE_POSE_MODELS,
    FeatureConfig,
    LocalizeConfig,
    MatchConfig,
    PathStateConfig,
    RelativePoseConfig,
    TeachConfig,
    migrate_vision_keys,
    renamed_vision_key,
)
from shared.config import (
    SIM_TABLE,
    FtpConfig,
    LogConfig,
    MavlinkConfig,
    from_mapping,
    load_toml,
)
from shared.errors import ConfigError

__all__ = [
    "BASE_LOST_ACTIONS",
    "CONTROL_LAWS",
    "FRONT_END_METHODS",
    "POLE_DOMAINS",
    "RELATIVE_POSE_MODELS",
    "CameraSourceConfig",
    "ControlConfig",
    "EstimatorConfig",
    "FeatureConfig",
    "FoxgloveConfig",
    "LocalizeConfig",
    "MatchConfig",
    "MissionConfig",
    "PathStateConfig",
    "PioneerDriverConfig",
    "RelativePoseConfig",
    "SafetyConfig",
    "SwitchingConfig",
    "TeachConfig",
    "TeleopConfig",
    "VideoConfig",
    "VmnavConfig",
    "config_from_log",
    "load_config",
]


@dataclass(frozen=True, slots=True)
class VmnavConfig:
    """The robot application's config: one table per component (the file's top level)."""

    features: FeatureConfig = field(default_factory=FeatureConfig)
    matching: MatchConfig = field(default_factory=MatchConfig)
    path_state: PathStateConfig = field(default_factory=PathStateConfig)
    teach: TeachConfig = field(default_factory=TeachConfig)
    localize: LocalizeConfig = field(default_factory=LocalizeConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    switching: SwitchingConfig = field(default_factory=SwitchingConfig)
    mission: MissionConfig = field(default_factory=MissionConfig)
    pioneer: PioneerDriverConfig = field(default_factory=PioneerDriverConfig)
    camera: CameraSourceConfig = field(default_factory=CameraSourceConfig)
    mavlink: MavlinkConfig = field(default_factory=MavlinkConfig)
    ftp: FtpConfig = field(default_factory=FtpConfig)
    log: LogConfig = field(default_factory=LogConfig)
    teleop: TeleopConfig = field(default_factory=TeleopConfig)
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    video: VideoConfig = field(default_factory=VideoConfig)
    foxglove: FoxgloveConfig = field(default_factory=FoxgloveConfig)


#: Tables of the layout before the simulator's tables left the robot's config: the old
#: dotted key, where the table lives now, and why.
MOVED_TABLES: tuple[tuple[str, str, str], ...] = (
    (f"{SIM_TABLE}.camera", "camera.mount",
     "the camera mount is the robot's; a simulation places its camera there too"),
    ("teach_driver", f"{SIM_TABLE}.teach_driver", "the scripted teach driver is the simulator's"),
)
#: Keys that no longer exist: the old dotted key and what replaced it, and why.
REPLACED_KEYS: tuple[tuple[str, str], ...] = (
    ("localize.min_matches",
     "localize.min_inliers and localize.min_inlier_ratio (a key image is accepted on the "
     "inliers of a relative pose, never on a match count)"),
)


def load_config(path: str | Path | None) -> VmnavConfig:
    """Load the robot's tables of a vmnav TOML config file; ``None`` gives the defaults.

    Raises:
        ConfigError: naming the file, table and key at fault; a table of
            :data:`MOVED_TABLES` names where it lives now, a pixel-valued vision key
            (:data:`robot.config.vision.RENAMED_VISION_KEYS`) its angle, a key of
            :data:`REPLACED_KEYS` what replaced it.
    """
    if path is None:
        return VmnavConfig()
    data = load_toml(path)
    for old, new, why in MOVED_TABLES:
        if _lookup(data, old) is not None:
            raise ConfigError(path, f"{old}: moved to [{new}] ({why})")
    renamed = renamed_vision_key(data)
    if renamed is not None:
        raise ConfigError(path, f"{renamed[0]}: renamed to {renamed[1]} (vision windows are "
                                "angles on the sphere now, docs/front-end.md)")
    for old, new in REPLACED_KEYS:
        if _lookup(data, old) is not None:
            raise ConfigError(path, f"{old}: no longer exists, replaced by {new}")
    return from_mapping(VmnavConfig, {k: v for k, v in data.items() if k != SIM_TABLE},
                        str(path))


def config_from_log(data: Mapping[str, Any], source: str, key_path: str) -> VmnavConfig:
    """The config a field log stored (``dataclasses.asdict`` of :class:`VmnavConfig`).

    A log written before the simulator's tables left the robot's config holds them
    too (``sim``, ``teach_driver``) and the camera mount in ``sim.camera``: the mount
    becomes ``camera.mount`` and the simulator's tables, which the robot never used,
    are dropped, so such a log replays as it ran. Vision windows logged in pixels
    become the angles they were on the default lens (:func:`migrate_vision_keys`). Keys
    of :data:`REPLACED_KEYS` are dropped: their replacements take their defaults.

    Raises:
        ConfigError: a key unknown in both layouts, a bad value (at ``key_path``).
    """
    if SIM_TABLE in data:
        old = dict(data)
        sim = old.pop(SIM_TABLE)
        old.pop("teach_driver", None)
        camera = old.get("camera", {})
        if isinstance(sim, Mapping) and "camera" in sim and isinstance(camera, Mapping):
            old["camera"] = {**camera, "mount": sim["camera"]}
        data = old
    for dotted, _ in REPLACED_KEYS:
        data = _without(data, dotted)
    return from_mapping(VmnavConfig, migrate_vision_keys(data), source, key_path)


def _without(data: Mapping[str, Any], dotted: str) -> Mapping[str, Any]:
    """``data`` without the dotted key ``dotted`` (copied where it changes)."""
    head, _, rest = dotted.partition(".")
    if head not in data:
        return data
    if not rest:
        return {k: v for k, v in data.items() if k != head}
    inner = data[head]
    if not isinstance(inner, Mapping):
        return data
    return {**data, head: _without(inner, rest)}


def _lookup(data: Mapping[str, Any], dotted: str) -> Any:
    """The value at dotted key ``dotted`` of nested tables, or None."""
    value: Any = data
    for key in dotted.split("."):
        if not isinstance(value, Mapping) or key not in value:
            return None
        value = value[key]
    return value
