"""A vehicle's video stream, found through the MAVLink camera protocol (``shared.mavlink.camera``).

Rules:

1. A vehicle has a stream when a camera component of its system beat lately (within
   :data:`CAMERA_LOST_NS`; a vehicle just found gets :data:`CAMERA_WAIT_NS` for its
   camera's first beat); otherwise there is nothing to ask, and the answer is a one-line
   :class:`~ground.station.GroundError`.
2. The station asks that camera for VIDEO_STREAM_INFORMATION of its first stream
   (REQUEST_MESSAGE, ACK first, then the message) and reads the URI, size and rate; a
   refusal, no answer, or a stream this station cannot open (not ``http://``) is a
   one-line error.
3. A URI with a wildcard host (a robot serving on every interface) gets the address the
   vehicle's packets come from (:func:`shared.mavlink.camera.reachable_uri`).
"""

from __future__ import annotations

import dataclasses

from ground.station import GroundError, GroundStation
from shared.clock import NS_PER_S
from shared.mavlink.camera import STREAM_ID, VideoStream, reachable_uri, stream_from_message
from shared.mavlink.commands.gcs import result_name
from shared.mavlink.dialect import mavlink

#: A camera not heard for this long is gone (rule 1): its HEARTBEAT comes every second, ns.
CAMERA_LOST_NS = 5 * NS_PER_S
#: How long to wait for a camera's HEARTBEAT when none was heard yet (a vehicle just found:
#: its camera beats every second), ns.
CAMERA_WAIT_NS = 1_500_000_000
#: How long to wait for the message once its request was accepted, s.
MESSAGE_WAIT_S = 2.0
_NAME = "VIDEO_STREAM_INFORMATION"


def find_video_stream(station: GroundStation) -> VideoStream:
    """The video stream of the vehicle ``station`` talks to (module rules).

    Raises:
        GroundError: no camera heard, refused, unanswered, or a stream that cannot be opened.
    """
    vehicle = station.vehicle
    if vehicle is None:
        raise GroundError("no vehicle to ask for its video stream yet")
    def heard() -> list[int]:
        now_ns = station.clock.now_ns()
        return sorted(c for c, t in vehicle.cameras.items() if now_ns - t < CAMERA_LOST_NS)

    who = f"vehicle {vehicle.system_id}"
    if not heard() and not station.run_until(lambda: bool(heard()), CAMERA_WAIT_NS):
        raise GroundError(f"{who} has no camera stream (no camera HEARTBEAT for "
                          f"{CAMERA_LOST_NS // NS_PER_S} s; vmnav robot serves one with --video)")
    camera = heard()[0]
    old = vehicle.telemetry.get(_NAME)
    done = station.command_to(camera, mavlink.MAV_CMD_REQUEST_MESSAGE,
                              mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, STREAM_ID)
    if not done.accepted:
        raise GroundError(f"{who}'s camera {camera} answered the request for its video stream "
                          f"with {result_name(done.result)}")

    def arrived() -> bool:
        msg = vehicle.telemetry.get(_NAME)
        return msg is not old and msg.get_srcComponent() == camera

    if not station.run_until(arrived, round(MESSAGE_WAIT_S * NS_PER_S)):
        raise GroundError(f"{who}'s camera {camera} accepted the request but sent no "
                          f"{_NAME} within {MESSAGE_WAIT_S:g} s")
    try:
        stream = stream_from_message(vehicle.telemetry[_NAME])
    except ValueError as e:
        raise GroundError(f"{who}'s camera {camera}: {e}") from None
    host = vehicle.peer[0] if vehicle.peer is not None else None
    return dataclasses.replace(stream, uri=reachable_uri(stream.uri, host))
