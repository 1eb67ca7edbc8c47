"""The robot's device configs: the Pioneer's ARIA driver, the camera with its mount, the
camera's live view, and the live topics served to Foxglove.

Tables ``[pioneer]``, ``[camera]`` (``[camera.mount]``), ``[video]`` and ``[foxglove]`` of a
vmnav config file (:mod:`robot.config`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from shared.config import AriaLinkConfig, CameraMountConfig, require


@dataclass(frozen=True, slots=True)
class PioneerDriverConfig:
    """The robot-side ARIA driver (robot.pioneer): transport, connect sequence, reconnection.

    Motion limits are pushed to the robot after connect as ARIA does (SETV, SETA, SETRV,
    SETRA; aria-protocol.md §3), capped by the tops the robot's CONFIG reply announces.
    Defaults: MobileSim's p3at model (0.6 m/s, 0.75 rad/s, accel 0.3 / decel 0.6 m/s²,
    1.74 rad/s², rounded to whole wire units).
    """

    url: str = "/dev/ttyUSB0"
    """The robot's address (``shared.link_address``): ``serial:DEVICE[:BAUD]`` or a device
    path, ``pty:PATH``, ``tcp:HOST:PORT``; also pyserial URLs (``socket://HOST:8101``,
    ``loop://``)."""
    baud: int = 38400
    """Configured serial rate, baud, unless ``url`` gives one. Connect attempts on a device
    alternate 9600 (ARCOS after power-up) and this rate (aria-protocol.md §9); TCP and
    URLs with a scheme ignore it."""
    write_timeout_s: float = 0.5
    """A write that cannot finish in this long means the link is gone, s."""
    connect_timeout_s: float = 1.5
    """A TCP host that has not answered a connect in this long is unreachable, s (a host
    on the LAN answers in milliseconds)."""
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
    command_timeout_ns: int = 300_000_000
    """The command watchdog under the robot's loop: a non-zero velocity command older than
    this is never refreshed; the driver sends VEL 0 and RVEL 0 and holds zero until the
    next command, ns. The loop re-commands on every frame, so this must exceed its longest
    normal frame period (a camera at 15 frames/s: 67 ms); a loop stalled longer stops the
    robot (issue 15)."""
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
            "baud", "write_timeout_s", "connect_timeout_s", "service_period_ns", "config_retry_ns",
            "config_wait_ns",
            "command_refresh_ns", "command_timeout_ns", "reconnect_initial_ns", "reconnect_max_ns",
            "noise_report_period_ns", "report_timeout_ns", "max_speed_m_s", "max_omega_rad_s",
            "accel_m_s2", "decel_m_s2", "rot_accel_rad_s2", "rot_decel_rad_s2",
        ):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.reconnect_max_ns >= self.reconnect_initial_ns,
                f"reconnect_max_ns ({self.reconnect_max_ns}) must be >= reconnect_initial_ns "
                f"({self.reconnect_initial_ns})")



@dataclass(frozen=True, slots=True)
class CameraSourceConfig:
    """The robot's camera (``robot.camera``): ``cv2.VideoCapture`` on a device, file or URL,
    and where the camera sits on the robot.

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
    mount: CameraMountConfig = field(default_factory=CameraMountConfig)
    """Where the camera sits on the robot (``[camera.mount]``): the vision lifts pixels to
    bearings in the robot's frame with it, and a simulation of this robot places its
    camera there."""

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



@dataclass(frozen=True, slots=True)
class VideoConfig:
    """The robot's live view (``vmnav robot --video``, :mod:`robot.video`): what its camera
    sees as MJPEG over HTTP, smaller and slower than the camera, advertised to ground
    stations through the MAVLink camera protocol. Table ``[video]``.

    The robot's loop hands a frame over at most every ``frame_period_ns`` and never waits;
    the server's client threads scale, draw and encode it.
    """

    width_px: int = 400
    """Frames are scaled down to this wide, px (the aspect kept; a narrower camera's frames
    stay as they are)."""
    frame_period_ns: int = 200_000_000
    """At most one frame this often, ns (5 frames/s)."""
    jpeg_quality: int = 70
    """cv2.IMWRITE_JPEG_QUALITY of the frames, 1-100."""
    max_clients: int = 4
    """Viewers served at once; more get HTTP 503 at once."""

    def __post_init__(self) -> None:
        require(16 <= self.width_px <= 4096, f"width_px must be in 16..4096, got {self.width_px}")
        require(self.frame_period_ns >= 10_000_000,
                f"frame_period_ns must be >= 10 ms (10000000), got {self.frame_period_ns}")
        require(1 <= self.jpeg_quality <= 100,
                f"jpeg_quality must be in 1..100, got {self.jpeg_quality}")
        require(1 <= self.max_clients <= 64,
                f"max_clients must be in 1..64, got {self.max_clients}")


@dataclass(frozen=True, slots=True)
class FoxgloveConfig:
    """The robot's live topics over the Foxglove WebSocket protocol (``vmnav robot
    --foxglove``, :mod:`robot.foxglove_bridge`): the field log's topics and schemas, live,
    for Foxglove or Lichtblick. Table ``[foxglove]``.

    The robot's loop hands frames and cycles over by reference and never waits; one thread
    encodes them, and the server drops a slow client's oldest messages.
    """

    address: str = ""
    """Where to serve: ``PORT`` or ``HOST:PORT`` (host 127.0.0.1 unless given; 0 picks a
    free port; a host off this machine needs ``--insecure``); empty: not served.
    ``--foxglove`` overrides it."""
    frame_period_ns: int = 100_000_000
    """At most one camera image (and its annotations) this often, ns of frame time
    (10 frames/s); servo state, commands and transforms go out every frame."""
    jpeg_quality: int = 80
    """cv2.IMWRITE_JPEG_QUALITY of the camera images, 1-100."""
    client_backlog_messages: int = 256
    """Messages queued per client (about 2 s of every topic); a client too slow for them
    loses the oldest (the SDK's ``message_backlog_size``)."""

    def __post_init__(self) -> None:
        require(self.frame_period_ns >= 10_000_000,
                f"frame_period_ns must be >= 10 ms (10000000), got {self.frame_period_ns}")
        require(1 <= self.jpeg_quality <= 100,
                f"jpeg_quality must be in 1..100, got {self.jpeg_quality}")
        require(16 <= self.client_backlog_messages <= 65536,
                f"client_backlog_messages must be in 16..65536, got "
                f"{self.client_backlog_messages}")
