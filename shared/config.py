"""Per-component configuration: frozen dataclasses, loaded from TOML and validated.

Every field has a default, a unit in its name where it has one, and a doc comment.
Cores receive these objects; only entry points read files. A config file is TOML
with one table per component::

    [sim]
    world = "campus"
    seed = 7

    [sim.body]
    max_speed_m_s = 0.5

Unknown keys, wrong types and out-of-range values raise :class:`ConfigError`
naming the file, the table and the key.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from shared.errors import ConfigError

T = TypeVar("T")


# ---------------------------------------------------------------------------
# Generic loading: mapping -> frozen dataclass, with type and range checks.
# ---------------------------------------------------------------------------


def load_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file.

    Raises:
        ConfigError: the file is missing, unreadable or not valid TOML (message
            names the file and TOML's own line/column).
    """
    path = Path(path)
    try:
        with path.open("rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise ConfigError(path, "file not found") from None
    except OSError as e:
        raise ConfigError(path, f"cannot read: {e.strerror}") from None
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(path, f"not valid TOML: {e}") from None


def from_mapping(cls: type[T], data: Mapping[str, Any], source: str, key_path: str = "") -> T:
    """Build dataclass ``cls`` from ``data``, checking keys and types.

    Supported field types: ``bool``, ``int``, ``float`` (ints accepted, NaN and
    infinities refused), ``str``, ``X | None``, nested dataclasses (TOML tables),
    ``tuple[float, ...]``, ``tuple[X, ...]`` of dataclasses (arrays of tables) and
    fixed tuples such as ``tuple[float, float]``. Missing keys take the field's
    default. ``__post_init__`` may raise :class:`ConfigError`, ``ValueError`` or
    ``TypeError``; all are re-raised as :class:`ConfigError` at ``where``.

    Args:
        cls: a dataclass type.
        data: the parsed TOML table.
        source: where the data came from (a file path), for messages.
        key_path: the dotted key of ``data`` inside the file (``""`` at the top).

    Raises:
        ConfigError: ``"<source>: <key>: <problem>"``.
    """
    where = _at(key_path)
    if not isinstance(data, Mapping):
        raise ConfigError(source, f"{where}expected a table, got {_describe(data)}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(
            source, f"{where}unknown key '{unknown[0]}' (known: {', '.join(sorted(fields))})"
        )
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        if name in data:
            kwargs[name] = _convert(hints[name], data[name], source, _join(key_path, name))
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(source, f"{where}missing required key '{name}'")
    try:
        return cls(**kwargs)
    except (ValueError, TypeError) as e:
        raise ConfigError(source, f"{where}{e}") from None


def _at(key_path: str) -> str:
    return f"{key_path}: " if key_path else ""


def _join(key_path: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{key_path}[{key}]"
    return f"{key_path}.{key}" if key_path else key


def _describe(value: Any) -> str:
    return "a table" if isinstance(value, dict) else f"{type(value).__name__} {value!r}"


def _convert(tp: Any, value: Any, source: str, key_path: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)

    def bad(expected: str) -> ConfigError:
        return ConfigError(source, f"{key_path}: expected {expected}, got {_describe(value)}")

    if origin in (types.UnionType, typing.Union):
        if value is None and type(None) in args:
            return None
        (inner,) = [a for a in args if a is not type(None)]
        return _convert(inner, value, source, key_path)
    if dataclasses.is_dataclass(tp):
        return from_mapping(tp, value, source, key_path)  # type: ignore[arg-type]
    if tp is bool:
        if not isinstance(value, bool):
            raise bad("true or false")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise bad("an integer")
        return value
    if tp is float:
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise bad("a finite number")
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise bad("a string")
        return value
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise bad("an array")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(
                _convert(args[0], v, source, _join(key_path, i)) for i, v in enumerate(value)
            )
        if len(value) != len(args):
            raise bad(f"an array of {len(args)} values")
        return tuple(
            _convert(a, v, source, _join(key_path, i))
            for i, (a, v) in enumerate(zip(args, value, strict=True))
        )
    raise TypeError(f"from_mapping cannot convert to {tp!r} (at {key_path})")


def require(condition: bool, message: str) -> None:
    """Raise ``ValueError(message)`` unless ``condition``; for ``__post_init__``.

    :func:`from_mapping` turns it into a :class:`ConfigError` naming the file and table.
    """
    if not condition:
        raise ValueError(message)


# ---------------------------------------------------------------------------
# ARIA link (shared.aria.session, both roles).
# ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class AriaLinkConfig:
    """Timing policy of one ARIA link. Defaults: stock ARIA and ARCOS (aria-protocol.md §3, §7)."""

    sync_reply_timeout_ns: int = 1_000_000_000
    """Host: wait this long for each SYNC reply before restarting at SYNC0, ns (ARIA: 1000 ms)."""
    sync_attempts: int = 6
    """Host: SYNC0s sent before the connect fails (ARIA gives up after 6, about 6.4 s)."""
    pulse_period_ns: int = 500_000_000
    """Host: send PULSE after this long without sending anything, ns (ARIA: 500 ms)."""
    link_timeout_ns: int = 8_000_000_000
    """Host: no SIP for this long while open means the link is lost, ns (ARIA: 8000 ms)."""
    sip_period_ns: int = 100_000_000
    """Robot: SIP cycle, ns (ARCOS and MobileSim: 100 ms; report it in CONFIG's SipCycle)."""
    watchdog_timeout_ns: int = 2_000_000_000
    """Robot: no client packet for this long while open trips the watchdog, ns (ARCOS: 2 s)."""
    frame_timeout_ns: int = 100_000_000
    """Both: abandon a partial frame after this long without a new byte, ns (ARIA: 100 ms)."""

    def __post_init__(self) -> None:
        for name in (
            "sync_reply_timeout_ns",
            "pulse_period_ns",
            "link_timeout_ns",
            "sip_period_ns",
            "watchdog_timeout_ns",
            "frame_timeout_ns",
        ):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.sync_attempts >= 1, f"sync_attempts must be >= 1, got {self.sync_attempts}")


@dataclass(frozen=True, slots=True)
class PioneerDriverConfig:
    """The robot-side ARIA driver (robot.pioneer): transport, connect sequence, reconnection.

    Motion limits are pushed to the robot after connect as ARIA does (SETV, SETA, SETRV,
    SETRA; aria-protocol.md §3), capped by the tops the robot's CONFIG reply announces.
    Defaults: MobileSim's p3at model (0.6 m/s, 0.75 rad/s, accel 0.3 / decel 0.6 m/s²,
    1.74 rad/s², rounded to whole wire units).
    """

    url: str = "/dev/ttyUSB0"
    """pyserial URL of the robot: a device or pty path, ``socket://host:8101`` or ``loop://``."""
    baud: int = 38400
    """Configured serial rate, baud. Connect attempts on a device alternate 9600 (ARCOS
    after power-up) and this rate (aria-protocol.md §9); URLs with a scheme ignore it."""
    write_timeout_s: float = 0.5
    """A write that cannot finish in this long means the link is gone, s."""
    link: AriaLinkConfig = field(default_factory=AriaLinkConfig)
    """Session timers: SYNC retries, PULSE, link-loss timeout."""
    service_period_ns: int = 10_000_000
    """The driver's I/O thread services the link this often, ns."""
    config_retry_ns: int = 200_000_000
    """Re-request CONFIG this often until the reply comes, ns (ARIA: about 200 ms)."""
    config_wait_ns: int = 1_000_000_000
    """Go on without a CONFIG reply after this long, ns (ARIA: 1000 ms)."""
    command_refresh_ns: int = 500_000_000
    """Re-send VEL/RVEL this often while moving or until the robot reports it stopped, ns
    (ARIA's state reflection: 500 ms); covers packets lost on a noisy line."""
    reconnect_initial_ns: int = 500_000_000
    """First wait before re-opening a lost link, ns; doubles per failure in a row."""
    reconnect_max_ns: int = 8_000_000_000
    """Longest wait between re-open attempts, ns."""
    noise_report_period_ns: int = 1_000_000_000
    """Report corrupt and unexpected input at most this often, ns."""
    report_timeout_ns: int = 1_000_000_000
    """No SIP for this long and the base is "not reporting" (``BaseState.reporting``): the
    robot stops and applies ``MissionConfig.base_lost_action``, ns. Ten SIP cycles, half
    the robot's watchdog; the link itself is given up only after ``link.link_timeout_ns``."""
    max_speed_m_s: float = 0.6
    """SETV: translational speed limit, m/s."""
    max_omega_rad_s: float = math.radians(43)
    """SETRV: rotational speed limit, rad/s."""
    accel_m_s2: float = 0.3
    """SETA: translational acceleration, m/s²."""
    decel_m_s2: float = 0.6
    """SETA (negative): translational deceleration, m/s²."""
    rot_accel_rad_s2: float = math.radians(100)
    """SETRA: rotational acceleration, rad/s²."""
    rot_decel_rad_s2: float = math.radians(100)
    """SETRA (negative): rotational deceleration, rad/s²."""

    def __post_init__(self) -> None:
        require(bool(self.url.strip()), "url must not be empty")
        for name in (
            "baud", "write_timeout_s", "service_period_ns", "config_retry_ns", "config_wait_ns",
            "command_refresh_ns", "reconnect_initial_ns", "reconnect_max_ns",
            "noise_report_period_ns", "report_timeout_ns", "max_speed_m_s", "max_omega_rad_s",
            "accel_m_s2", "decel_m_s2", "rot_accel_rad_s2", "rot_decel_rad_s2",
        ):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.reconnect_max_ns >= self.reconnect_initial_ns,
                f"reconnect_max_ns ({self.reconnect_max_ns}) must be >= reconnect_initial_ns "
                f"({self.reconnect_initial_ns})")


@dataclass(frozen=True, slots=True)
class CameraSourceConfig:
    """The robot's camera (``robot.camera``): ``cv2.VideoCapture`` on a device, file or URL.

    A live source (a device or a URL) that fails is reopened after a backoff, forever;
    a file ends. A stall shorter than ``read_timeout_ns`` resumes on the same connection.
    """

    source: str = "0"
    """What cv2.VideoCapture opens: a device index (``"0"``), a video file, or a URL
    (``http://host:8080/stream.mjpg``, ``rtsp://...``)."""
    open_timeout_ns: int = 5_000_000_000
    """A URL that does not open within this long fails (at start-up: an error; later: a
    reconnect attempt), ns (OpenCV FFMPEG's CAP_PROP_OPEN_TIMEOUT_MSEC, whole ms)."""
    read_timeout_ns: int = 5_000_000_000
    """A URL silent for this long is dropped and reopened, ns; also bounds the wait for
    the first frame at start-up (CAP_PROP_READ_TIMEOUT_MSEC, whole ms)."""
    max_failed_reads: int = 5
    """This many failed reads in a row mean the source is gone (a file ended, a stream
    closed); fewer are undecodable frames, skipped."""
    reconnect_initial_ns: int = 250_000_000
    """First wait before reopening a lost live source, ns; doubles per failure in a row."""
    reconnect_max_ns: int = 4_000_000_000
    """Longest wait between reopen attempts, ns."""

    def __post_init__(self) -> None:
        require(bool(self.source.strip()), "source must not be empty")
        for name in ("open_timeout_ns", "read_timeout_ns"):
            require(getattr(self, name) >= 1_000_000,
                    f"{name} must be >= 1 ms (1000000), got {getattr(self, name)}")
        for name in ("max_failed_reads", "reconnect_initial_ns", "reconnect_max_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.reconnect_max_ns >= self.reconnect_initial_ns,
                f"reconnect_max_ns ({self.reconnect_max_ns}) must be >= reconnect_initial_ns "
                f"({self.reconnect_initial_ns})")


# ---------------------------------------------------------------------------
# Simulator components.
# ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class BodyConfig:
    """The simulated Pioneer 3-AT body (defaults: P3-AT datasheet and MobileSim's model)."""

    length_m: float = 0.626
    """Length including bumpers, m (ARIA p3at params)."""
    width_m: float = 0.505
    """Width, m."""
    mass_kg: float = 12.0
    """Mass, kg."""
    max_speed_m_s: float = 0.7
    """Forward/backward speed limit, m/s."""
    max_omega_rad_s: float = math.radians(140.0)
    """Rotational speed limit, rad/s."""
    accel_m_s2: float = 0.3
    """Translational acceleration limit, m/s^2."""
    decel_m_s2: float = 0.6
    """Translational deceleration limit, m/s^2."""
    rot_accel_rad_s2: float = 1.74
    """Rotational acceleration (and deceleration) limit, rad/s^2."""
    stall_time_s: float = 0.3
    """Blocked motion for this long under a non-zero command reports a stall, s."""

    def __post_init__(self) -> None:
        for name in (
            "length_m",
            "width_m",
            "mass_kg",
            "max_speed_m_s",
            "max_omega_rad_s",
            "accel_m_s2",
            "decel_m_s2",
            "rot_accel_rad_s2",
            "stall_time_s",
        ):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")


@dataclass(frozen=True, slots=True)
class OdometryConfig:
    """Wheel odometry errors, kept apart from the ground truth."""

    trans_scale_sigma: float = 0.01
    """Std of the per-run translational scale error (wheel radius, slip), fraction."""
    rot_scale_sigma: float = 0.03
    """Std of the per-run rotational scale error (skid-steer slip), fraction."""
    trans_noise_m_s: float = 0.005
    """Std of white noise on the measured speed, per physics step, m/s."""
    rot_noise_rad_s: float = 0.005
    """Std of white noise on the measured turn rate, per physics step, rad/s."""

    def __post_init__(self) -> None:
        for name in ("trans_scale_sigma", "rot_scale_sigma", "trans_noise_m_s", "rot_noise_rad_s"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")


@dataclass(frozen=True, slots=True)
class CameraMountConfig:
    """Where the fisheye camera sits on the robot (robot frame: x forward, y left, z up)."""

    x_m: float = 0.2
    """Forward offset of the optical centre from the robot's centre, m."""
    y_m: float = 0.0
    """Leftward offset, m."""
    height_m: float = 0.3
    """Height of the optical centre above the floor, m."""
    yaw_deg: float = 0.0
    """Optical axis yaw, counter-clockwise from forward, degrees."""
    pitch_deg: float = 0.0
    """Optical axis pitch, up positive, degrees."""
    roll_deg: float = 0.0
    """Roll about the optical axis, degrees."""

    def __post_init__(self) -> None:
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        require(abs(self.pitch_deg) <= 90, f"pitch_deg must be within ±90, got {self.pitch_deg}")


@dataclass(frozen=True, slots=True)
class RenderConfig:
    """The fisheye renderer."""

    noise_sigma: float = 2.0
    """Std of additive Gaussian sensor noise, grey levels."""
    illumination_amplitude: float = 0.15
    """Peak relative change of the global illumination gain over time (0 = constant)."""
    illumination_period_s: float = 40.0
    """Period of the slow global illumination change, s."""

    def __post_init__(self) -> None:
        require(self.noise_sigma >= 0, f"noise_sigma must be >= 0, got {self.noise_sigma}")
        require(
            0 <= self.illumination_amplitude < 1,
            f"illumination_amplitude must be in [0, 1), got {self.illumination_amplitude}",
        )
        require(
            self.illumination_period_s > 0,
            f"illumination_period_s must be > 0, got {self.illumination_period_s}",
        )


@dataclass(frozen=True, slots=True)
class PeopleConfig:
    """People walking about: moving bodies that occlude landmarks and can bump the robot."""

    count: int = 0
    """Number of people."""
    speed_m_s: float = 1.0
    """Walking speed, m/s."""
    radius_m: float = 0.25
    """Body radius (a vertical cylinder), m."""
    height_m: float = 1.75
    """Body height, m."""
    avoid_robot: bool = True
    """Whether people yield to the robot (False: they walk into it, for bump scenarios)."""
    clearance_m: float = 0.8
    """Look-ahead: a person yields when moving this far on, relative to the robot, touches it, m."""
    yield_patience_s: float = 3.0
    """Time a person stands yielding before walking off to another goal, s."""

    def __post_init__(self) -> None:
        require(self.count >= 0, f"count must be >= 0, got {self.count}")
        require(self.speed_m_s >= 0, f"speed_m_s must be >= 0, got {self.speed_m_s}")
        require(self.radius_m > 0, f"radius_m must be > 0, got {self.radius_m}")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        require(self.clearance_m > 0, f"clearance_m must be > 0, got {self.clearance_m}")
        require(
            self.yield_patience_s >= 0,
            f"yield_patience_s must be >= 0, got {self.yield_patience_s}",
        )


@dataclass(frozen=True, slots=True)
class EmulatorConfig:
    """The emulated Pioneer 3-AT-SH (ARIA server, ``sim.pioneer``); aria-protocol.md §11."""

    name: str = "vmnav"
    """Robot name in the SYNC2 reply and the CONFIG packet ("MobileSim" would make ARIA
    treat the server as MobileSim)."""
    watchdog_stops: bool = True
    """Whether the watchdog (``link.watchdog_timeout_ns`` without a client packet) stops
    the robot until packets return (ARCOS) or only counts (MobileSim)."""
    battery_full_v: float = 13.0
    """Battery voltage at the start, V (a charged P3-AT pack)."""
    battery_empty_v: float = 11.0
    """The battery never reports less than this, V."""
    battery_drain_v_per_m: float = 0.0005
    """Voltage lost per metre of mean wheel travel, V/m (0.5 V per km)."""
    sonar_max_range_m: float = 5.0
    """Sonar range when nothing echoes, m (MobileSim reports 5000 mm)."""
    sonar_noise_m: float = 0.01
    """Std of Gaussian noise on each sonar range, m."""
    sonar_cycle_ns: int = 40_000_000
    """Each sonar array fires its next transducer this often, ns (both arrays together)."""
    link: AriaLinkConfig = field(default_factory=AriaLinkConfig)
    """The robot end's timing: SIP cycle, watchdog, frame timeout."""

    def __post_init__(self) -> None:
        require(
            0 < len(self.name) <= 20 and self.name.isascii() and self.name.isprintable(),
            f"name must be 1-20 printable ASCII characters, got {self.name!r}",
        )
        require(
            0 < self.battery_empty_v <= self.battery_full_v,
            f"battery_empty_v must be in (0, battery_full_v], got {self.battery_empty_v} "
            f"(battery_full_v {self.battery_full_v})",
        )
        require(
            self.battery_full_v < 25.5,
            f"battery_full_v must be < 25.5 V (one byte of decivolts), got {self.battery_full_v}",
        )
        for name in ("battery_drain_v_per_m", "sonar_noise_m"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(
            0 < self.sonar_max_range_m <= 65.0,
            f"sonar_max_range_m must be in (0, 65] (u16 mm), got {self.sonar_max_range_m}",
        )
        require(self.sonar_cycle_ns > 0, f"sonar_cycle_ns must be > 0, got {self.sonar_cycle_ns}")


@dataclass(frozen=True, slots=True)
class SimConfig:
    """The simulated world and everything in it."""

    world: str = "lab"
    """A built-in world name (``lab``, ``campus``) or the path of a world TOML file."""
    seed: int = 1
    """Seed of every random draw in the simulation (landmarks, noise, people)."""
    physics_dt_ns: int = 10_000_000
    """Fixed physics step, ns (pymunk wants a fixed step)."""
    frame_period_ns: int = 66_666_667
    """Camera frame period, ns (15 frames/s, as in the paper)."""
    landmark_density_scale: float = 1.0
    """Multiplies the world's landmark densities (1 = as the world file says)."""
    camera_file: str | None = None
    """Calibration JSON of the simulated camera; None = the default 800x600, 185 degree model."""
    body: BodyConfig = field(default_factory=BodyConfig)
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    camera: CameraMountConfig = field(default_factory=CameraMountConfig)
    render: RenderConfig = field(default_factory=RenderConfig)
    people: PeopleConfig = field(default_factory=PeopleConfig)
    emulator: EmulatorConfig = field(default_factory=EmulatorConfig)

    def __post_init__(self) -> None:
        require(self.physics_dt_ns > 0, f"physics_dt_ns must be > 0, got {self.physics_dt_ns}")
        require(
            self.frame_period_ns >= self.physics_dt_ns,
            f"frame_period_ns ({self.frame_period_ns}) must be >= "
            f"physics_dt_ns ({self.physics_dt_ns})",
        )
        require(
            self.landmark_density_scale >= 0,
            f"landmark_density_scale must be >= 0, got {self.landmark_density_scale}",
        )


# ---------------------------------------------------------------------------
# Robot vision components.
# ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class FeatureConfig:
    """Harris corners and their ZNCC patch descriptors (Courbon et al. 2008, sec. III-A).

    Defaults follow OpenCV's Harris (``k`` = 0.04, 3x3 block, 3x3 Sobel) and the
    reference benchmark (300 corners, 11x11 patches).
    """

    max_corners: int = 300
    """Keep at most this many corners, strongest Harris response first."""
    quality_level: float = 0.01
    """Reject corners whose response is below this fraction of the frame's strongest, in (0, 1)."""
    min_distance_px: float = 8.0
    """Minimum Euclidean distance between two corners, px (greedy, strongest first)."""
    block_size_px: int = 3
    """Side of the window summing the gradient products of the Harris matrix, px (odd)."""
    harris_k: float = 0.04
    """Harris & Stephens' k in det(M) - k trace(M)^2 (dimensionless)."""
    patch_size_px: int = 11
    """Side P of the square ZNCC patch, px (odd, >= 3); a descriptor has P*P values."""
    subpixel_half_window_px: int = 3
    """Half side of the cv2.cornerSubPix window, px; 0 keeps integer corner positions."""

    def __post_init__(self) -> None:
        require(self.max_corners >= 1, f"max_corners must be >= 1, got {self.max_corners}")
        require(
            0 < self.quality_level < 1, f"quality_level must be in (0, 1), got {self.quality_level}"
        )
        require(
            self.min_distance_px >= 0, f"min_distance_px must be >= 0, got {self.min_distance_px}"
        )
        require(
            self.block_size_px >= 3 and self.block_size_px % 2 == 1,
            f"block_size_px must be odd and >= 3, got {self.block_size_px}",
        )
        require(0 < self.harris_k < 0.25, f"harris_k must be in (0, 0.25), got {self.harris_k}")
        require(
            self.patch_size_px >= 3 and self.patch_size_px % 2 == 1,
            f"patch_size_px must be odd and >= 3, got {self.patch_size_px}",
        )
        require(
            self.subpixel_half_window_px >= 0,
            f"subpixel_half_window_px must be >= 0, got {self.subpixel_half_window_px}",
        )


@dataclass(frozen=True, slots=True)
class MatchConfig:
    """ZNCC matching in a search window with the unicity (mutual best) constraint.

    The paper gives no numbers; the defaults are the reference benchmark's window
    and a threshold measured on synthetic pairs (``robot/vision/bench_features.py``).
    """

    search_radius_px: float | None = 40.0
    """Candidates satisfy |dx| <= r and |dy| <= r, px; None searches the whole image
    (code only: TOML cannot write None, so a file can only set a finite radius)."""
    min_zncc: float = 0.8
    """Reject matches whose ZNCC score is below this, in [-1, 1]."""
    max_distance_ratio: float | None = None
    """Lowe's ratio test on patch distances sqrt(2 - 2 ZNCC), in (0, 1]; None = off."""

    def __post_init__(self) -> None:
        require(
            self.search_radius_px is None or self.search_radius_px > 0,
            f"search_radius_px must be > 0 or None, got {self.search_radius_px}",
        )
        require(-1 <= self.min_zncc <= 1, f"min_zncc must be in [-1, 1], got {self.min_zncc}")
        require(
            self.max_distance_ratio is None or 0 < self.max_distance_ratio <= 1,
            f"max_distance_ratio must be in (0, 1] or None, got {self.max_distance_ratio}",
        )


# ---------------------------------------------------------------------------
# Teaching: key image selection (robot) and the scripted teach driver (sim).
# ---------------------------------------------------------------------------


def _tracking_match_config() -> MatchConfig:
    return MatchConfig(search_radius_px=20.0, min_zncc=0.7)


@dataclass(frozen=True, slots=True)
class TeachConfig:
    """Key image selection (Courbon et al. 2008, sec. II-C) and joining new paths to a memory.

    The default M was chosen in the ``lab`` world at the teach driver's default speed:
    it gives about two key images per metre on straight corridors (the measured
    spacing is printed by ``vmnav teach``).
    """

    min_tracked_points: int = 50
    """M: a key image shares at least this many points tracked from the previous one."""
    min_tracked_fraction: float = 0.35
    """In (0, 1]. A key image with few corners needs only this fraction of them tracked
    (the threshold is min(M, ceil(fraction * corners))): in a sparse scene a fixed M
    would force a key image at every frame. It must stay well below the share of
    the live points a single frame matches, 0.46-0.77 in the ``lab`` and ``campus``
    worlds: at 0.5 the ``campus`` corridor got key images 2 cm apart, too close for a
    key pair (see :mod:`robot.teach`, rule 3)."""
    max_turn_deg: float = 15.0
    """A key image is at most this far turned (odometric yaw) from the previous one, deg:
    the repeat matches the next key image in a window of ``PathStateConfig.matching``'s
    radius (120 px; a yaw of 1 deg moves the image centre by about 4 px), so a long
    gap in a turn leaves nothing to match (the ``campus`` U-turn had a 50 deg gap)."""
    max_missed_frames: int = 2
    """A tracked point survives this many consecutive frames without a match (detector blinks)."""
    tracking: MatchConfig = field(default_factory=_tracking_match_config)
    """Frame-to-frame matching of the tracked points (small window, mutual best)."""
    junction_min_matches: int = 40
    """A path's end joins a key image of another path with at least this many matches
    (two unrelated views share up to about 25 chance matches without a search window)."""
    min_path_length_m: float = 0.2
    """A path taught over the link must span at least this much odometry, m; a shorter
    drive (a teach started and stopped in place) is refused instead of stored."""

    def __post_init__(self) -> None:
        require(self.min_path_length_m >= 0,
                f"min_path_length_m must be >= 0, got {self.min_path_length_m}")
        require(
            self.min_tracked_points >= 1,
            f"min_tracked_points must be >= 1, got {self.min_tracked_points}",
        )
        require(
            self.max_missed_frames >= 0,
            f"max_missed_frames must be >= 0, got {self.max_missed_frames}",
        )
        require(0 < self.max_turn_deg <= 180,
                f"max_turn_deg must be in (0, 180], got {self.max_turn_deg}")
        require(
            self.junction_min_matches >= 1,
            f"junction_min_matches must be >= 1, got {self.junction_min_matches}",
        )


@dataclass(frozen=True, slots=True)
class TeachDriverConfig:
    """The simulator's scripted human-like teach driver (``sim.teach_driver``).

    Pure pursuit of the route shifted sideways by a smooth random wander, at a
    cruise speed that drifts slowly: a person steering by eye, never exactly on
    the line, never exactly at constant speed.
    """

    speed_m_s: float = 0.3
    """Mean cruise speed, m/s."""
    speed_variation: float = 0.1
    """Peak relative deviation of the cruise speed (smooth in distance), fraction in [0, 1)."""
    wander_amplitude_m: float = 0.04
    """Peak lateral offset of the pursued line from the route, m."""
    wander_wavelength_m: tuple[float, float] = (2.0, 6.0)
    """Range of the wavelengths of the wander and the speed drift, along the route, m."""
    lookahead_m: float = 0.6
    """Pure-pursuit look-ahead distance, m."""
    max_omega_rad_s: float = 0.6
    """Turn-rate limit, rad/s (a person turns slowly while teaching)."""
    goal_tolerance_m: float = 0.1
    """The drive ends within this distance of the route's last waypoint, m."""

    def __post_init__(self) -> None:
        for name in ("speed_m_s", "lookahead_m", "max_omega_rad_s", "goal_tolerance_m"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(
            0 <= self.speed_variation < 1,
            f"speed_variation must be in [0, 1), got {self.speed_variation}",
        )
        require(
            self.wander_amplitude_m >= 0,
            f"wander_amplitude_m must be >= 0, got {self.wander_amplitude_m}",
        )
        low, high = self.wander_wavelength_m
        require(
            0 < low <= high,
            f"wander_wavelength_m must be (low, high) with 0 < low <= high, got {(low, high)}",
        )


#: Models of :class:`RelativePoseConfig`: "planar" (upright planar 2-point), "general"
#: (5-point), "auto" (planar, and 5-point as well when the planar fit looks poor).
RELATIVE_POSE_MODELS = ("planar", "general", "auto")


@dataclass(frozen=True, slots=True)
class RelativePoseConfig:
    """Robust relative pose from unit bearings (reference visual-navigation.md, sec. 4.4).

    RANSAC over minimal solvers (PoseLib's upright planar 2-point, or 5-point),
    scored by the angular Sampson error on the sphere, then refined on the inliers.
    Thresholds are angles: 1 px is about 5.7 mrad on the default 185 degree lens.
    """

    model: str = "auto"
    """One of ``RELATIVE_POSE_MODELS``; the planar model needs level bearings (y vertical)."""
    inlier_threshold_rad: float = 0.012
    """A correspondence is an inlier when its angular Sampson error is below this, rad."""
    huber_scale_rad: float = 0.006
    """Residuals beyond this are down-weighted (Huber loss) in the refinement, rad."""
    confidence: float = 0.999
    """RANSAC stops when an all-inlier sample was drawn with this probability."""
    max_iterations: int = 256
    """Most minimal samples drawn for the planar model."""
    max_iterations_general: int = 1024
    """Most minimal samples drawn for the general (5-point) model."""
    min_inliers: int = 8
    """A fit with fewer inliers is not ok (the planar model has 2 degrees of freedom)."""
    min_planar_inlier_ratio: float = 0.5
    """Model "auto": below this planar inlier ratio the 5-point model is tried too."""
    refine_passes: int = 2
    """Refine on the inliers and re-select them this many times (0: the best RANSAC
    hypothesis, with its inliers)."""

    def __post_init__(self) -> None:
        require(
            self.model in RELATIVE_POSE_MODELS,
            f"model must be one of {', '.join(RELATIVE_POSE_MODELS)}, got {self.model!r}",
        )
        require(
            0 < self.inlier_threshold_rad < 0.5,
            f"inlier_threshold_rad must be in (0, 0.5), got {self.inlier_threshold_rad}",
        )
        require(
            0 < self.huber_scale_rad <= self.inlier_threshold_rad,
            f"huber_scale_rad must be in (0, inlier_threshold_rad], got {self.huber_scale_rad}",
        )
        require(0 < self.confidence < 1, f"confidence must be in (0, 1), got {self.confidence}")
        require(self.max_iterations >= 1, f"max_iterations must be >= 1, got {self.max_iterations}")
        require(
            self.max_iterations_general >= 1,
            f"max_iterations_general must be >= 1, got {self.max_iterations_general}",
        )
        require(self.min_inliers >= 5, f"min_inliers must be >= 5, got {self.min_inliers}")
        require(
            0 <= self.min_planar_inlier_ratio <= 1,
            f"min_planar_inlier_ratio must be in [0, 1], got {self.min_planar_inlier_ratio}",
        )
        require(self.refine_passes >= 0, f"refine_passes must be >= 0, got {self.refine_passes}")


def _state_match_config() -> MatchConfig:
    return MatchConfig(search_radius_px=120.0)


@dataclass(frozen=True, slots=True)
class PathStateConfig:
    """Lateral and angular error from the current view and two key images (DESIGN.md sec. 5.5)."""

    relative_pose: RelativePoseConfig = field(default_factory=RelativePoseConfig)
    """Relative pose of two key images, and of the two-view state (refined)."""
    pose_before_resection: RelativePoseConfig = field(
        default_factory=lambda: RelativePoseConfig(refine_passes=1))
    """Relative pose of the current view and the next key image in the three-view state:
    the planar resection refines it further, so one refinement pass suffices."""
    min_parallax_deg: float = 2.0
    """Triangulated key-pair points need at least this angle between their two rays, degrees."""
    max_point_distance_m: float = 30.0
    """Triangulated points farther than this from the next key image are dropped, m."""
    point_threshold_rad: float = 0.02
    """A 3D point is an inlier of the current pose when it reprojects within this angle, rad."""
    min_points: int = 3
    """The three-view state needs at least this many inlier key-pair points in the current
    view (the epipolar matches fix yaw and direction; the points fix the scale, one degree
    of freedom, so 3 leave two for redundancy; measured on simulator frames)."""
    max_odometry_disagreement_deg: float = 15.0
    """A key pair is refused when the visual baseline direction and the teach odometry's
    differ by more than this, degrees."""
    matching: MatchConfig = field(default_factory=_state_match_config)
    """Matching of the current view with the next key image, and of two key images
    (``robot.vision.frame_state``): a window wide enough for a robot 0.5 m and 20 degrees
    off the key image's view (on 234 such views in ``lab``, with the key pairs matched
    directly, a +-40 px window left 26 % without a state, +-120 px 3 %)."""

    def __post_init__(self) -> None:
        require(
            0 <= self.min_parallax_deg < 90,
            f"min_parallax_deg must be in [0, 90), got {self.min_parallax_deg}",
        )
        require(
            self.max_point_distance_m > 0,
            f"max_point_distance_m must be > 0, got {self.max_point_distance_m}",
        )
        require(
            0 < self.point_threshold_rad < 0.5,
            f"point_threshold_rad must be in (0, 0.5), got {self.point_threshold_rad}",
        )
        require(self.min_points >= 2, f"min_points must be >= 2, got {self.min_points}")
        require(
            0 < self.max_odometry_disagreement_deg <= 180,
            f"max_odometry_disagreement_deg must be in (0, 180], got "
            f"{self.max_odometry_disagreement_deg}",
        )


def _localize_match_config() -> MatchConfig:
    return MatchConfig(search_radius_px=None, min_zncc=0.8)


@dataclass(frozen=True, slots=True)
class LocalizeConfig:
    """Localization of an image in the visual memory (Courbon et al. 2008, sec. II-D).

    A global prefilter ranks every key image by the similarity of patch-normalised
    thumbnails (Milford and Wyeth's SeqSLAM / QVPR teach-and-repeat normalisation),
    then the paper's rule (most Harris + ZNCC matches) picks among the best
    ``candidates``. Defaults measured on the ``lab`` world (``tools/localize_bench.py``).
    """

    candidates: int = 20
    """Key images verified by full matching, the prefilter's best first."""
    min_matches: int = 25
    """The winner is a localization (``ok``) with at least this many matches (two unrelated
    views share up to about 25 chance matches without a search window)."""
    matching: MatchConfig = field(default_factory=_localize_match_config)
    """Full matching of the query against a candidate (no window: the view may have turned)."""
    prefilter_rows_fraction: float = 0.6
    """Thumbnail rows used from the top, fraction in (0, 1]: the floor below the horizon is
    near, bare and changes most with a lateral offset."""
    prefilter_window_px: int = 9
    """Side of the window of the thumbnail's patch normalisation, thumbnail px (odd)."""
    prefilter_max_shift_px: int = 6
    """The query thumbnail is compared shifted sideways by up to this, thumbnail px
    (a turn of the robot shifts the view sideways; 6 px of 80 is about 14 degrees)."""

    def __post_init__(self) -> None:
        require(self.candidates >= 1, f"candidates must be >= 1, got {self.candidates}")
        require(self.min_matches >= 1, f"min_matches must be >= 1, got {self.min_matches}")
        require(0 < self.prefilter_rows_fraction <= 1,
                f"prefilter_rows_fraction must be in (0, 1], got {self.prefilter_rows_fraction}")
        require(self.prefilter_window_px >= 3 and self.prefilter_window_px % 2 == 1,
                f"prefilter_window_px must be odd and >= 3, got {self.prefilter_window_px}")
        require(self.prefilter_max_shift_px >= 0,
                f"prefilter_max_shift_px must be >= 0, got {self.prefilter_max_shift_px}")


# ---------------------------------------------------------------------------
# Route following (robot): control law, estimator, key image switching, mission.
# ---------------------------------------------------------------------------

#: Control laws of :class:`ControlConfig`: "paper" (Courbon et al. 2008, eq. 2) and
#: "paper+ff" (eq. 2 plus a feed-forward of the teach path's curvature).
CONTROL_LAWS = ("paper", "paper+ff")

#: Domains of :attr:`ControlConfig.double_pole`: "distance" (1/m, the chained form's own
#: variable) or "time" (1/s, converted to 1/m by dividing by the speed).
POLE_DOMAINS = ("distance", "time")


@dataclass(frozen=True, slots=True)
class ControlConfig:
    """The path-following law (Courbon et al. 2008, sec. III-C and IV; DESIGN.md sec. 5.6).

    Gains put a double pole at g (1/m) on the lateral error's response to the
    distance travelled: Kp = g^2, Kd = 2 g. The paper says only "a double pole
    located at value 0.3". Read in the distance domain (0.3 1/m) it takes 10.8 m to
    bring a 0.3 m offset under 5 cm (reference visual-navigation.md sec. 1.2), while
    the paper's own run (280 key images over about 500 s at 0.2 m/s, so one every
    ~0.36 m) is said to regulate the errors "to zero for each key view". We read it
    as a time-domain pole, 0.3 1/s = 1.5 1/m at 0.2 m/s (2.3 m to 5 cm); set
    ``pole_domain = "distance"`` for the other reading.
    """

    law: str = "paper"
    """One of ``CONTROL_LAWS``: the paper's eq. (2), or eq. (2) plus curvature feed-forward."""
    speed_m_s: float = 0.2
    """Forward speed V, m/s (paper: 200 mm/s)."""
    max_omega_rad_s: float = math.radians(10.0)
    """Bound on |omega|, rad/s (paper: 10 deg/s). With V it bounds the turn radius from
    below at V / max_omega (1.15 m at the defaults)."""
    double_pole: float = 0.3
    """The closed loop's double pole, in 1/m or 1/s as ``pole_domain`` says (paper: 0.3)."""
    pole_domain: str = "time"
    """One of ``POLE_DOMAINS``: the unit of ``double_pole``."""

    def __post_init__(self) -> None:
        require(self.law in CONTROL_LAWS,
                f"law must be one of {', '.join(CONTROL_LAWS)}, got {self.law!r}")
        require(self.pole_domain in POLE_DOMAINS,
                f"pole_domain must be one of {', '.join(POLE_DOMAINS)}, got {self.pole_domain!r}")
        for name in ("speed_m_s", "max_omega_rad_s", "double_pole"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")

    @property
    def pole_1_m(self) -> float:
        """The double pole g in the distance domain, 1/m."""
        if self.pole_domain == "distance":
            return self.double_pole
        return self.double_pole / self.speed_m_s


@dataclass(frozen=True, slots=True)
class EstimatorConfig:
    """The Kalman filter over (s, y, theta) (``robot.estimator``): odometry predicts, vision
    updates.

    Measurement noise defaults come from the three-view simulation of reference
    visual-navigation.md sec. 1.2 (median |dy| about 1 cm, p90 about 3 cm; median
    |dtheta| 0.5 to 0.8 degrees, p90 up to 2.4 degrees).
    """

    sigma_y_m: float = 0.02
    """Std of the vision estimate of y, m."""
    sigma_theta_rad: float = math.radians(1.5)
    """Std of the vision estimate of theta, rad."""
    sigma_s_m: float = 0.05
    """Std of the vision estimate of s (along-track), m."""
    process_var_position_m2_per_m: float = 1e-4
    """Growth of var(s) and var(y) per metre driven, m^2/m (wheel slip, unmodelled motion)."""
    process_var_theta_rad2_per_m: float = 1e-4
    """Growth of var(theta) per metre driven, rad^2/m (uneven wheels, ground)."""
    rotation_scale_sigma: float = 0.03
    """Std of the odometry's rotation error as a fraction of the turn measured (skid
    steering slips in turns; the simulator draws 3 %)."""
    gate_chi2: float | None = 16.3
    """A vision estimate (s, y, theta) whose squared Mahalanobis distance to the prediction
    exceeds this is rejected (16.3 = chi-square, 3 degrees of freedom, p = 0.999); None
    accepts all (code only: TOML cannot write None)."""
    init_min_points: int = 10
    """A vision estimate initialises the filter (ungated: at a start, after a junction
    crossing or LOST) only with at least this many triangulated key-pair points behind it;
    three points once gave y = 1.05 m for a robot on the path."""
    lost_timeout_ns: int = 2_000_000_000
    """No accepted vision estimate for this long means LOST, ns (30 frames at 15 Hz, 0.4 m
    of odometry alone at 0.2 m/s)."""

    def __post_init__(self) -> None:
        for name in ("sigma_y_m", "sigma_theta_rad", "sigma_s_m", "lost_timeout_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        for name in ("process_var_position_m2_per_m", "process_var_theta_rad2_per_m",
                     "rotation_scale_sigma"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(self.gate_chi2 is None or self.gate_chi2 > 0,
                f"gate_chi2 must be > 0 or None, got {self.gate_chi2}")
        require(self.init_min_points >= 0,
                f"init_min_points must be >= 0, got {self.init_min_points}")


@dataclass(frozen=True, slots=True)
class SwitchingConfig:
    """When the next key image counts as reached (Courbon et al. 2008, sec. IV; reference
    visual-navigation.md sec. 1.3)."""

    err_image_max_px: float = 20.0
    """Reached when errImageMax is below this, px (paper: 20 px)."""
    image_error_within_m: float = 0.25
    """...and, when the frame has an along-track estimate s, the robot is at most this far
    before the key image, m (a large value is the paper's rule). Far landmarks (the ``campus``
    courtyard's facades) keep errImageMax under 20 px up to 0.75 m before a key image:
    the switch came early and the next key image, turned 15 deg, looked 30 cm off."""
    pass_margin_m: float = 0.0
    """Reached when the along-track coordinate s (relative to the key image, negative
    before it) is at least this, m."""
    hold_frames: int = 2
    """A rule must hold on this many consecutive frames with evidence before it switches
    (hysteresis against a single noisy frame)."""

    def __post_init__(self) -> None:
        require(self.err_image_max_px > 0,
                f"err_image_max_px must be > 0, got {self.err_image_max_px}")
        require(self.image_error_within_m > 0,
                f"image_error_within_m must be > 0, got {self.image_error_within_m}")
        require(self.pass_margin_m >= 0, f"pass_margin_m must be >= 0, got {self.pass_margin_m}")
        require(self.hold_frames >= 1, f"hold_frames must be >= 1, got {self.hold_frames}")


#: What a mission run does when the base stops reporting (a cut ARIA cable, a Pioneer
#: that went quiet; :attr:`MissionConfig.base_lost_action`). The robot stops either way
#: (and the Pioneer's own watchdog stops it 2 s after the last packet it got): "hold"
#: ends the run and waits in HOLD for the operator, "continue" pauses the run and goes
#: on when the base reports again.
BASE_LOST_ACTIONS = ("hold", "continue")


@dataclass(frozen=True, slots=True)
class MissionConfig:
    """Give-up policy of the mission state machine (``robot.mission``)."""

    localize_timeout_ns: int = 30_000_000_000
    """LOCALIZING for this long without success fails the mission, ns (paper: one
    localization took 6.5 s)."""
    localize_attempts: int = 5
    """This many failed localizations in a row fail the mission."""
    relocalize_timeout_ns: int = 20_000_000_000
    """LOST for this long without relocalizing fails the mission, ns."""
    relocalize_attempts: int = 10
    """This many failed relocalizations in one LOST episode fail the mission."""
    base_lost_action: str = "continue"
    """One of ``BASE_LOST_ACTIONS``: what a mission run does when the base stops reporting."""

    def __post_init__(self) -> None:
        for name in ("localize_timeout_ns", "localize_attempts", "relocalize_timeout_ns",
                     "relocalize_attempts"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.base_lost_action in BASE_LOST_ACTIONS,
                f"base_lost_action must be one of {', '.join(BASE_LOST_ACTIONS)}, "
                f"got {self.base_lost_action!r}")


#: What the vehicle does when the ground station's heartbeat stops
#: (:attr:`MavlinkConfig.gcs_lost_action`): "hold" stops and waits, "continue" carries on
#: with the mission in force.
GCS_LOST_ACTIONS = ("hold", "continue")


@dataclass(frozen=True, slots=True)
class MavlinkConfig:
    """MAVLink protocol timing (``shared.mavlink``) and the vehicle's ground-link policy.

    Mission timeouts and the retry count are the devguide's recommendations
    (mission.md, "Timeouts and Retries": 1500 ms, 250 ms for items, 5 retries).
    """

    mission_timeout_ns: int = 1_500_000_000
    """Wait this long for a mission reply (request, count, ack) before resending, ns."""
    mission_item_timeout_ns: int = 250_000_000
    """Wait this long for a requested mission item before re-requesting it, ns."""
    mission_retries: int = 10
    """Resend a mission message this many times without an answer, then give up. The
    devguide suggests 5; at 20 % loss each way a request and its answer both pass with
    p = 0.64, and 5 retries failed about 5 % of 25-exchange sessions (10: about 1e-4)."""
    mission_max_items: int = 1000
    """A mission upload with more items is refused with MAV_MISSION_NO_SPACE."""
    param_timeout_ns: int = 1_000_000_000
    """Wait this long for a parameter reply, or for progress of a full download, ns."""
    param_retries: int = 10
    """Resend a parameter request this many times without progress, then give up (10 for
    the same reason as ``mission_retries``)."""
    param_stream_period_ns: int = 20_000_000
    """Gap between PARAM_VALUEs streamed after PARAM_REQUEST_LIST, ns (50 per second)."""
    gcs_lost_action: str = "hold"
    """One of ``GCS_LOST_ACTIONS``: what the robot does when the ground heartbeat stops."""
    system_id: int = 1
    """The vehicle's MAVLink system id, 1..255 (unique per robot; its component id is 1)."""
    heartbeat_period_ns: int = 1_000_000_000
    """The vehicle's HEARTBEAT period, ns (1 Hz: ground stations call a vehicle lost after
    about 4-5 missed beats)."""
    gcs_timeout_ns: int = 5_000_000_000
    """No ground-station HEARTBEAT for this long (after one was seen) is the GCS failsafe, ns."""
    status_period_ns: int = 1_000_000_000
    """Default period of SYS_STATUS, BATTERY_STATUS and MISSION_CURRENT, ns."""
    odometry_period_ns: int = 250_000_000
    """Default period of ODOMETRY and NAV_CONTROLLER_OUTPUT, ns."""
    servo_status_period_ns: int = 500_000_000
    """Default period of VISUAL_SERVO_STATUS, ns."""
    home_period_ns: int = 10_000_000_000
    """Default period of HOME_POSITION (once the home is known), ns."""
    min_stream_period_ns: int = 50_000_000
    """Shortest period SET_MESSAGE_INTERVAL may set for one message, ns (caps the link load)."""
    service_period_ns: int = 10_000_000
    """Period of the vehicle's UDP I/O thread, ns."""

    def __post_init__(self) -> None:
        for name in ("mission_timeout_ns", "mission_item_timeout_ns", "mission_max_items",
                     "param_timeout_ns", "param_stream_period_ns", "heartbeat_period_ns",
                     "gcs_timeout_ns", "status_period_ns", "odometry_period_ns",
                     "servo_status_period_ns", "home_period_ns", "min_stream_period_ns",
                     "service_period_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(1 <= self.system_id <= 255, f"system_id must be in 1..255, got {self.system_id}")
        for name in ("mission_retries", "param_retries"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(self.mission_max_items <= 65535,
                f"mission_max_items must be <= 65535 (uint16 seq), got {self.mission_max_items}")
        require(self.gcs_lost_action in GCS_LOST_ACTIONS,
                f"gcs_lost_action must be one of {', '.join(GCS_LOST_ACTIONS)}, "
                f"got {self.gcs_lost_action!r}")


@dataclass(frozen=True, slots=True)
class FtpConfig:
    """MAVLink FTP (``shared.mavlink.ftp``): client retries and pacing, server limits.

    Client defaults follow pymavlink's mavftp (retry 0.5 s, write queue 5) with the
    devguide's 6 retries (mavlink-vehicle.md §1.6); packets carry the full 239 bytes.
    """

    ack_timeout_ns: int = 500_000_000
    """Client: resend a request after this long without its reply, ns."""
    retries: int = 6
    """Client: resend a request this many times without a reply, then give up."""
    burst_size_bytes: int = 239
    """Client: data bytes asked for per burst-read and read packet (1..239)."""
    write_size_bytes: int = 239
    """Client: data bytes per WriteFile packet (1..239)."""
    max_in_flight: int = 5
    """Client: ReadFile (gap) or WriteFile requests outstanding at once."""
    max_sessions: int = 5
    """Server: open file sessions at once (MAVProxy's max_sessions default)."""
    burst_packets: int = 32
    """Server: packets per BurstReadFile reply; the client asks again for the rest."""
    session_timeout_ns: int = 30_000_000_000
    """Server: a session unused this long is closed (an unfinished upload dropped), ns."""
    upload_limit_bytes: int = 8 * 1024 * 1024
    """Server: largest file accepted in the upload area, bytes (the goal photo)."""

    def __post_init__(self) -> None:
        for name in ("ack_timeout_ns", "max_in_flight", "max_sessions", "burst_packets",
                     "session_timeout_ns", "upload_limit_bytes"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.retries >= 0, f"retries must be >= 0, got {self.retries}")
        require(self.max_sessions <= 256, f"max_sessions must be <= 256, got {self.max_sessions}")
        for name in ("burst_size_bytes", "write_size_bytes"):
            value = getattr(self, name)
            require(1 <= value <= 239, f"{name} must be in 1..239, got {value}")


LOG_COMPRESSIONS = ("none", "lz4", "zstd")


@dataclass(frozen=True, slots=True)
class LogConfig:
    """Field logging to MCAP (``shared.logs``): what is kept, flushing and rotation.

    The loss window of a killed process is one flush period plus what waits in the
    queue (mcap-logging.md §1 "Crash behaviour"): a chunk reaches the file only when
    it is full or flushed, and 1 MiB of telemetry alone is minutes of data.
    """

    output_dir: str = "logs"
    """Folder of the log files; created if missing."""
    frame_rate_hz: float = 15.0
    """Camera frames logged per second at most, per image topic; faster frames are skipped."""
    jpeg_quality: int = 85
    """JPEG quality of logged frames, 1-100 (cv2.IMWRITE_JPEG_QUALITY)."""
    flush_period_ns: int = 500_000_000
    """Close the open chunk and flush the file at least this often, ns (at most 1 s).
    Half the 1 s budget: the other half covers a writer thread behind on a busy machine."""
    fsync: bool = True
    """``os.fsync`` after each flush, so a power cut also loses at most a flush period."""
    chunk_size_bytes: int = 1024 * 1024
    """Close a chunk once it holds this many uncompressed bytes (about 0.7 s of images)."""
    compression: str = "lz4"
    """Chunk compression, one of ``LOG_COMPRESSIONS``. JPEG does not compress (zstd gains
    1-4 %) and zstd stalls the writer 8-10 ms per chunk; lz4 shrinks telemetry 4x."""
    rotate_size_bytes: int = 1_000_000_000
    """Start the next numbered file once a file reaches this size, bytes (overshoots by up
    to one chunk)."""
    rotate_period_ns: int = 600_000_000_000
    """Start the next numbered file once a file spans this much log time, ns (10 min)."""
    queue_messages: int = 256
    """Messages waiting for the writer thread at most; more are dropped and counted
    (about 3 s of 15 frames/s plus 50 Hz telemetry)."""
    retry_period_ns: int = 5_000_000_000
    """After a write error (disk full, folder gone) try a new file this often, ns."""
    replay_frames: bool = False
    """Log every frame a mission cycle consumed losslessly (PNG, whatever ``frame_rate_hz``),
    so that ``vmnav replay`` reproduces the estimates exactly; JPEG frames replay only
    approximately. An 800x600 simulated frame costs the writer thread about 4 ms and the file
    180 kB as PNG (JPEG: 1 ms, 40 kB)."""

    def __post_init__(self) -> None:
        require(bool(self.output_dir.strip()), "output_dir must not be empty")
        for name in ("frame_rate_hz", "flush_period_ns", "chunk_size_bytes", "rotate_size_bytes",
                     "rotate_period_ns", "queue_messages", "retry_period_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(1 <= self.jpeg_quality <= 100,
                f"jpeg_quality must be in 1..100, got {self.jpeg_quality}")
        require(self.flush_period_ns <= 1_000_000_000,
                f"flush_period_ns must be <= 1 s (1000000000), got {self.flush_period_ns}")
        require(self.compression in LOG_COMPRESSIONS,
                f"compression must be one of {', '.join(LOG_COMPRESSIONS)}, "
                f"got {self.compression!r}")


@dataclass(frozen=True, slots=True)
class TeleopConfig:
    """Driving by hand over the link (MANUAL_CONTROL in MANUAL mode, ``robot.runtime``)."""

    max_speed_m_s: float = 0.4
    """Forward speed at full stick (x = +-1000), m/s."""
    max_omega_rad_s: float = 0.7853981633974483
    """Turn rate at full stick (r = +-1000), rad/s (45 deg/s)."""
    deadman_ns: int = 500_000_000
    """No MANUAL_CONTROL for this long stops the robot, ns (ground stations send 10-50 Hz;
    QGroundControl's joystick sends at least every 50 ms while held)."""
    frame_timeout_ns: int = 500_000_000
    """No camera frame for this long stops the base until frames return, ns."""

    def __post_init__(self) -> None:
        for name in ("max_speed_m_s", "max_omega_rad_s", "deadman_ns", "frame_timeout_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")


@dataclass(frozen=True, slots=True)
class VmnavConfig:
    """The whole configuration file: one table per component."""

    sim: SimConfig = field(default_factory=SimConfig)
    features: FeatureConfig = field(default_factory=FeatureConfig)
    matching: MatchConfig = field(default_factory=MatchConfig)
    path_state: PathStateConfig = field(default_factory=PathStateConfig)
    teach: TeachConfig = field(default_factory=TeachConfig)
    teach_driver: TeachDriverConfig = field(default_factory=TeachDriverConfig)
    localize: LocalizeConfig = field(default_factory=LocalizeConfig)
    control: ControlConfig = field(default_factory=ControlConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    switching: SwitchingConfig = field(default_factory=SwitchingConfig)
    mission: MissionConfig = field(default_factory=MissionConfig)
    pioneer: PioneerDriverConfig = field(default_factory=PioneerDriverConfig)
    camera: CameraSourceConfig = field(default_factory=CameraSourceConfig)
    mavlink: MavlinkConfig = field(default_factory=MavlinkConfig)
    log: LogConfig = field(default_factory=LogConfig)
    teleop: TeleopConfig = field(default_factory=TeleopConfig)


def load_config(path: str | Path | None) -> VmnavConfig:
    """Load a vmnav TOML config file; ``None`` gives the defaults.

    Raises:
        ConfigError: naming the file, table and key at fault.
    """
    if path is None:
        return VmnavConfig()
    return from_mapping(VmnavConfig, load_toml(path), str(path))
