"""The camera protocol (devguide camera.md), both ends: how a ground station finds the robot's
video stream.

Theory of operation
-------------------

The robot's fisheye camera is a MAVLink camera of its own: component
:data:`CAMERA_COMPONENT_ID` (``MAV_COMP_ID_CAMERA``, 100) of the robot's system, beside the
autopilot (component 1), with its own HEARTBEAT (``MAV_TYPE_CAMERA``,
``MAV_AUTOPILOT_INVALID``) at the autopilot's period. That is how ground stations find
cameras: QGroundControl and MAVSDK's camera plugin start a camera for each component that
beats as one (``MAV_COMP_ID_CAMERA`` .. ``CAMERA6``), then ask it for CAMERA_INFORMATION;
reference/mavlink-vehicle.md sec. 1.7. The alternative of common.xml, a camera "attached
to an autopilot" answered by component 1 with ``camera_device_id`` 1-6, is newer and fewer
ground stations know it; and a camera component is only there while the robot serves its
camera (``vmnav robot --video``), so a station that hears no camera HEARTBEAT knows at
once that there is no stream, without asking.

The camera answers, through its own :class:`~shared.mavlink.commands.vehicle.
CommandDispatcher` (ACK first, then the message; anything else UNSUPPORTED):

* REQUEST_MESSAGE (512) for CAMERA_INFORMATION (259), VIDEO_STREAM_INFORMATION (269,
  param2: the stream, 0 for all, 1 the only one), VIDEO_STREAM_STATUS (270) and HEARTBEAT
  (0: a station discovering components, as ``vmnav ground`` does, hears the camera at
  once rather than at its next beat); a stream id that does not exist is DENIED;
* the deprecated REQUEST_CAMERA_INFORMATION (521), REQUEST_VIDEO_STREAM_INFORMATION (2504)
  and REQUEST_VIDEO_STREAM_STATUS (2505, param1 the stream), which older ground stations
  send.

**The stream's type.** ``VIDEO_STREAM_TYPE`` has no MJPEG and no HTTP: RTSP (0), RTP over
UDP (1, "URI gives the port number"), MPEG on TCP (2), MPEG-TS (3, "URI gives the port
number": the ground station listens on UDP) and WHEP (4). Ours is a TCP connection the
ground station opens to a URI, which is what ``VIDEO_STREAM_TYPE_TCP_MPEG`` describes; the
encoding says ``VIDEO_STREAM_ENCODING_UNKNOWN`` (neither H.264 nor H.265), and the URI
(``http://HOST:PORT/stream.mjpg``) says the rest. A ground station that plays
TCP_MPEG as an MPEG transport stream (QGroundControl) cannot show it; ``vmnav ground web``
and anything that opens HTTP (a browser, ``cv2.VideoCapture``, ffplay) can.

A stream served on every interface (``0.0.0.0`` or ``::``) is advertised with that address:
the robot does not know which of its addresses a station reaches; the station puts the
robot's own address in its place (:func:`reachable_uri`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit, urlunsplit

from shared.mavlink.commands.vehicle import CommandReply, CommandRequest, Handler
from shared.mavlink.dialect import Message, mavlink

#: The camera's component id (``MAV_COMP_ID_CAMERA``).
CAMERA_COMPONENT_ID = mavlink.MAV_COMP_ID_CAMERA
#: The id of the camera's one video stream (VIDEO_STREAM_INFORMATION ``stream_id``).
STREAM_ID = 1
#: The stream's type (module docstring).
STREAM_TYPE = mavlink.VIDEO_STREAM_TYPE_TCP_MPEG
#: Longest URI VIDEO_STREAM_INFORMATION carries (``char[160]``).
URI_CHARS = 160
#: What a ground station may open of a URI it was given (module docstring).
URI_SCHEMES = frozenset({"http"})
_NAME_CHARS = 32
_WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})


@dataclass(frozen=True, slots=True)
class VideoStream:
    """The camera's stream as the protocol describes it.

    Attributes:
        uri: where to open it, ``http://HOST:PORT/stream.mjpg`` (at most 160 characters).
        width_px: frame width as served, px.
        height_px: frame height as served, px.
        rate_hz: frames per second at most, Hz.
        hfov_deg: horizontal field of view, whole degrees (0: not known).
        name: the stream's name (at most 32 characters).
        vendor: CAMERA_INFORMATION ``vendor_name`` (at most 32 characters).
        model: CAMERA_INFORMATION ``model_name`` (at most 32 characters).
    """

    uri: str
    width_px: int
    height_px: int
    rate_hz: float
    hfov_deg: int = 0
    name: str = "fisheye"
    vendor: str = "vmnav"
    model: str = "fisheye camera"

    def __post_init__(self) -> None:
        if len(self.uri) > URI_CHARS or not self.uri.isascii():
            raise ValueError(f"uri: at most {URI_CHARS} ASCII characters, got {self.uri!r:.80}")
        if not (0 < self.width_px <= 0xFFFF and 0 < self.height_px <= 0xFFFF):
            raise ValueError(f"size {self.width_px}x{self.height_px} px outside 1..65535")
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz}")
        if not 0 <= self.hfov_deg <= 0xFFFF:
            raise ValueError(f"hfov_deg outside 0..65535, got {self.hfov_deg}")
        for name in ("name", "vendor", "model"):
            text = getattr(self, name)
            if len(text) > _NAME_CHARS or not text.isascii():
                raise ValueError(f"{name}: at most {_NAME_CHARS} ASCII characters, "
                                 f"got {text!r:.40}")


# -- the camera's end ----------------------------------------------------------------------

def camera_heartbeat() -> mavlink.MAVLink_heartbeat_message:
    """The camera component's HEARTBEAT (module docstring)."""
    return mavlink.MAVLink_heartbeat_message(
        type=mavlink.MAV_TYPE_CAMERA, autopilot=mavlink.MAV_AUTOPILOT_INVALID, base_mode=0,
        custom_mode=0, system_status=mavlink.MAV_STATE_ACTIVE, mavlink_version=3)


def _padded(text: str, size: int = _NAME_CHARS) -> list[int]:
    """``text`` as a zero-padded ``uint8_t[size]`` array (CAMERA_INFORMATION's names)."""
    data = text.encode("ascii")
    return list(data) + [0] * (size - len(data))


def camera_information_message(stream: VideoStream, time_boot_ms: int) -> Message:
    """CAMERA_INFORMATION (259): a camera with a video stream and nothing else to set."""
    return mavlink.MAVLink_camera_information_message(
        time_boot_ms & 0xFFFFFFFF, _padded(stream.vendor), _padded(stream.model), 0,
        math.nan, math.nan, math.nan, stream.width_px, stream.height_px, 0,
        mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM, 0, b"")


def video_stream_information_message(stream: VideoStream) -> Message:
    """VIDEO_STREAM_INFORMATION (269) of the one stream, running."""
    return mavlink.MAVLink_video_stream_information_message(
        STREAM_ID, 1, STREAM_TYPE, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING, stream.rate_hz,
        stream.width_px, stream.height_px, 0, 0, stream.hfov_deg,
        stream.name.encode("ascii"), stream.uri.encode("ascii"),
        mavlink.VIDEO_STREAM_ENCODING_UNKNOWN)


def video_stream_status_message(stream: VideoStream) -> Message:
    """VIDEO_STREAM_STATUS (270) of the one stream, running."""
    return mavlink.MAVLink_video_stream_status_message(
        STREAM_ID, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING, stream.rate_hz, stream.width_px,
        stream.height_px, 0, 0, stream.hfov_deg)


def camera_handlers(stream: VideoStream, time_boot_ms: Callable[[], int]) -> dict[int, Handler]:
    """The camera component's command table (module docstring).

    Args:
        stream: what it serves.
        time_boot_ms: the vehicle's time since boot now, ms (CAMERA_INFORMATION's stamp).
    """

    def stream_message(stream_id: float, build: Callable[[VideoStream], Message]) \
            -> CommandReply:
        if not (math.isnan(stream_id) or stream_id in (0.0, float(STREAM_ID))):
            return CommandReply(mavlink.MAV_RESULT_DENIED)  # no such stream
        return CommandReply(mavlink.MAV_RESULT_ACCEPTED, (build(stream),))

    def camera_information(_: VideoStream) -> Message:
        return camera_information_message(stream, time_boot_ms())

    def request_message(r: CommandRequest) -> CommandReply:
        msg_id = r.params[0]
        if msg_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT:  # a station looking for components
            return CommandReply(mavlink.MAV_RESULT_ACCEPTED, (camera_heartbeat(),))
        if msg_id == mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION:
            return stream_message(math.nan, camera_information)
        if msg_id == mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION:
            return stream_message(r.params[1], video_stream_information_message)
        if msg_id == mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS:
            return stream_message(r.params[1], video_stream_status_message)
        return CommandReply(mavlink.MAV_RESULT_DENIED)  # a message this camera does not have

    def deprecated_information(r: CommandRequest) -> CommandReply:
        if r.params[0] != 1.0:  # "0: No action 1: Request camera capabilities"
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return stream_message(math.nan, camera_information)

    return {
        mavlink.MAV_CMD_REQUEST_MESSAGE: request_message,
        mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION: deprecated_information,
        mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION:
            lambda r: stream_message(r.params[0], video_stream_information_message),
        mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_STATUS:
            lambda r: stream_message(r.params[0], video_stream_status_message),
    }


# -- the ground station's end --------------------------------------------------------------

def is_camera_heartbeat(msg: Any) -> bool:
    """Whether ``msg`` is a camera component's HEARTBEAT (MAV_TYPE_CAMERA, or any HEARTBEAT
    from the camera component ids 100-105)."""
    return isinstance(msg, mavlink.MAVLink_heartbeat_message) and (
        msg.type == mavlink.MAV_TYPE_CAMERA
        or mavlink.MAV_COMP_ID_CAMERA <= msg.get_srcComponent() <= mavlink.MAV_COMP_ID_CAMERA6)


def stream_from_message(msg: Any) -> VideoStream:
    """The stream a VIDEO_STREAM_INFORMATION describes.

    Raises:
        ValueError: one line: not a stream this station can open (a URI that is not
            ``http://``, an empty one, a size of 0).
    """
    uri = _text(msg.uri)
    scheme = urlsplit(uri).scheme
    if scheme not in URI_SCHEMES:
        raise ValueError(f"stream {msg.stream_id} is {uri!r:.60} (type {msg.type}): "
                         f"only {', '.join(sorted(URI_SCHEMES))}:// streams can be shown")
    return VideoStream(uri, msg.resolution_h, msg.resolution_v,
                       msg.framerate if math.isfinite(msg.framerate) and msg.framerate > 0
                       else 1.0, msg.hfov, _text(msg.name)[:_NAME_CHARS])


def reachable_uri(uri: str, vehicle_host: str | None) -> str:
    """``uri`` with a wildcard host (``0.0.0.0``, ``::``) replaced by ``vehicle_host``, the
    address the vehicle's packets come from (module docstring); otherwise as it is."""
    parts = urlsplit(uri)
    if vehicle_host is None or (parts.hostname or "") not in _WILDCARD_HOSTS:
        return uri
    host = f"[{vehicle_host}]" if ":" in vehicle_host else vehicle_host
    netloc = host if parts.port is None else f"{host}:{parts.port}"
    return urlunsplit((parts.scheme, netloc, parts.path, parts.query, parts.fragment))


def _text(value: Any) -> str:
    """A ``char[]`` field as pymavlink gives it (str or bytes), up to its first NUL."""
    if isinstance(value, bytes):
        value = value.decode("ascii", "replace")
    return str(value).split("\0", 1)[0]
