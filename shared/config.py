"""Config machinery, and the config types more than one of robot/, ground/ and sim/ use.

Every config is a frozen dataclass: every field has a default, a unit in its name
where it has one, and a doc comment. Cores receive these objects; only entry points
read files. Each part keeps its own configs: the robot's in :mod:`robot.config`, the
simulator's in :mod:`sim.config`; this module holds the loading machinery and the
types two parts share (an ARIA link's timers, the camera mount, MAVLink, FTP, field
logs).

One TOML file configures everything, one table per component: the robot's tables at
the top level (read by :func:`robot.config.load_config`), the simulator's under
``[sim]`` (:data:`SIM_TABLE`, read by :func:`sim.config.load_sim_config`)::

    [control]
    speed_m_s = 0.25

    [camera.mount]
    pitch_deg = -5.0

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
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from shared.errors import ConfigError

T = TypeVar("T")

SIM_TABLE = "sim"
"""The config file's table of the simulator: :mod:`sim.config` reads it, the robot's
loader leaves it alone."""

IN_FILE = "in_file"
"""Field metadata key: a field with ``metadata={IN_FILE: False}`` is set by code (where
parts are put together), never by a file; :func:`from_mapping` treats its key as unknown."""


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
    default; fields marked not :data:`IN_FILE` always do. ``__post_init__`` may raise
    :class:`ConfigError`, ``ValueError`` or ``TypeError``; all are re-raised as
    :class:`ConfigError` at ``where``.

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
    fields = {f.name: f for f in dataclasses.fields(cls)  # type: ignore[arg-type]
              if f.metadata.get(IN_FILE, True)}
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
# ARIA link (shared.aria.session, both roles: the robot's driver, the sim's emulator).
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


# ---------------------------------------------------------------------------
# The camera mount: the robot's vision lifts pixels with it, the simulator's
# renderer places its camera with it.
# ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class CameraMountConfig:
    """Where the fisheye camera sits on the robot (robot frame: x forward, y left, z up).

    A property of the robot: its config holds it (``[camera.mount]``,
    :class:`robot.config.CameraSourceConfig`), and a simulation built for that robot
    places its camera there too (:attr:`sim.config.SimConfig.camera_mount`).
    """

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



# ---------------------------------------------------------------------------
# MAVLink and FTP (both ends: robot and ground station).
# ---------------------------------------------------------------------------


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
    """Server: packets per BurstReadFile reply; the client asks again for the rest. Only
    the peer that opened the session gets a burst; every other request gets one reply."""
    session_timeout_ns: int = 30_000_000_000
    """Server: a session unused this long is closed (an unfinished upload dropped), ns."""
    upload_limit_bytes: int = 8 * 1024 * 1024
    """Server: largest file accepted in the upload area, bytes (the goal photo); a larger
    upload is refused with NAK FailErrno EFBIG."""
    upload_total_bytes: int = 64 * 1024 * 1024
    """Server: the upload area's quota, bytes: its files plus the uploads in progress (held
    in RAM); an upload that would pass it is refused with NAK FailErrno ENOSPC."""
    resend_cache_peers: int = 64
    """Server: peers whose last request and reply are kept to answer a retry (least
    recently used forgotten first; at most 502 bytes of payload each)."""

    def __post_init__(self) -> None:
        for name in ("ack_timeout_ns", "max_in_flight", "max_sessions", "burst_packets",
                     "session_timeout_ns", "upload_limit_bytes", "upload_total_bytes",
                     "resend_cache_peers"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.retries >= 0, f"retries must be >= 0, got {self.retries}")
        require(self.max_sessions <= 256, f"max_sessions must be <= 256, got {self.max_sessions}")
        for name in ("burst_size_bytes", "write_size_bytes"):
            value = getattr(self, name)
            require(1 <= value <= 239, f"{name} must be in 1..239, got {value}")



# ---------------------------------------------------------------------------
# Field logs (robot and ground station).
# ---------------------------------------------------------------------------


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
    max_bytes: int = 10_000_000_000
    """Disk quota of one log (all its numbered files), bytes. Once reached, the bulky topics
    (camera frames and their annotations, MAVLink messages and raw frames) are no longer
    written (counted in ``LogStats.over_quota``) and one WARNING says so, in the file and
    on the console; state, commands, transforms, SIPs and events go on (a few kB/s)."""
    retain_max_bytes: int = 50_000_000_000
    """Size limit of the log folder, bytes: when a log file opens, the oldest of the log
    files vmnav wrote there are deleted until they hold at most this much (the files
    being written are never deleted; other files never; ``shared.logs.retention``).
    0: no size limit; else at least 1 MB (1000000)."""
    retain_max_age_days: float = 90.0
    """Age limit of the log folder, days: when a log file opens, the log files vmnav wrote
    there that were last modified longer ago than this are deleted. 0: no age limit;
    else at most 36500."""
    replay_frames: bool = False
    """Log every frame a mission cycle consumed losslessly (PNG, whatever ``frame_rate_hz``),
    so that ``vmnav replay`` reproduces the estimates exactly; JPEG frames replay only
    approximately. An 800x600 simulated frame costs the writer thread about 4 ms and the file
    180 kB as PNG (JPEG: 1 ms, 40 kB)."""

    def __post_init__(self) -> None:
        require(bool(self.output_dir.strip()), "output_dir must not be empty")
        for name in ("frame_rate_hz", "flush_period_ns", "chunk_size_bytes", "rotate_size_bytes",
                     "rotate_period_ns", "queue_messages", "retry_period_ns", "max_bytes"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(1 <= self.jpeg_quality <= 100,
                f"jpeg_quality must be in 1..100, got {self.jpeg_quality}")
        require(self.flush_period_ns <= 1_000_000_000,
                f"flush_period_ns must be <= 1 s (1000000000), got {self.flush_period_ns}")
        require(self.retain_max_bytes == 0 or self.retain_max_bytes >= 1_000_000,
                f"retain_max_bytes must be 0 (no limit) or at least 1000000 (1 MB), got "
                f"{self.retain_max_bytes}")
        require(math.isfinite(self.retain_max_age_days)
                and 0 <= self.retain_max_age_days <= 36500,
                f"retain_max_age_days must be 0 (no limit) or in (0, 36500] days, got "
                f"{self.retain_max_age_days}")
        require(self.compression in LOG_COMPRESSIONS,
                f"compression must be one of {', '.join(LOG_COMPRESSIONS)}, "
                f"got {self.compression!r}")


LOG_TABLE = "log"
"""The config file's table of :class:`LogConfig` (the robot's ``[log]``)."""


def load_log_config(path: str | Path | None) -> LogConfig:
    """The ``[log]`` table of a vmnav config file (other tables are left to their parts'
    loaders); ``None`` or no such table gives the defaults. The ground station's config.

    Raises:
        ConfigError: naming the file and the key at fault.
    """
    if path is None:
        return LogConfig()
    return from_mapping(LogConfig, load_toml(path).get(LOG_TABLE, {}), str(path), LOG_TABLE)
