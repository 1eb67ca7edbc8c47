"""The robot's own commands on the wire, in common.xml's user range (reference
mavlink-vehicle.md sec. 0.4 and 5): numbers and the path-name encoding, shared by the
vehicle (``robot.vehicle.user_commands``) and the ground station. Every ground
station can send them by number (MAVProxy ``long 31010 7``, MAVSDK
``MavlinkDirect.send_command``), as COMMAND_LONG or COMMAND_INT.

=========================  ==========================================================
``MAV_CMD_USER_1`` 31010   go to a photo: param1 = photo id N (integer 1..2^24). The
                           photo was uploaded over MAVLink FTP as ``/upload/N.<ext>``
                           (any extension, e.g. ``ftp put goal.jpg /upload/7.jpg``);
                           the robot localizes it in its memory and drives there
                           (``VehicleApp.goto_image`` with the local path)
``MAV_CMD_USER_2`` 31011   start teaching a visual path; param1..param7 carry its name
                           (:func:`params_from_name`; all 0 or NaN: the robot names it)
``MAV_CMD_USER_3`` 31012   stop teaching; the path joins the memory
=========================  ==========================================================

Results: ACCEPTED when the robot took the request, DENIED when it cannot now or a
parameter is malformed (a STATUSTEXT after the ACK says why). Progress shows in the
telemetry (HEARTBEAT mode, MISSION_CURRENT, VISUAL_SERVO_STATUS, STATUSTEXT). Go to a
photo is long-running: IN_PROGRESS while the robot looks the photo up, then ACCEPTED
with ``result_param2`` the key image it was found at, or FAILED
(``robot.vehicle.user_commands``).

Name encoding: up to :data:`NAME_BYTES` printable ASCII bytes, 3 per parameter in
order, each parameter the big-endian integer of its 3 bytes (0..2^24-1, exact in a
float32 and in COMMAND_INT's int32 x/y), zero-padded at the end.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from shared.mavlink.dialect import mavlink

GOTO_PHOTO = mavlink.MAV_CMD_USER_1
TEACH_START = mavlink.MAV_CMD_USER_2
TEACH_STOP = mavlink.MAV_CMD_USER_3
#: Their names, for messages.
NAMES = {GOTO_PHOTO: "GOTO_PHOTO", TEACH_START: "TEACH_START", TEACH_STOP: "TEACH_STOP"}

#: Longest path name a TEACH_START carries, bytes.
NAME_BYTES = 21
_BYTES_PER_PARAM = 3


def params_from_name(name: str) -> tuple[float, ...]:
    """The seven TEACH_START parameters carrying ``name`` (module docstring).

    Raises:
        ValueError: ``name`` is longer than :data:`NAME_BYTES` or not printable ASCII.
    """
    if len(name) > NAME_BYTES or not (name.isascii() and name.isprintable()):
        raise ValueError(f"path name {name!r}: at most {NAME_BYTES} printable ASCII characters")
    data = name.encode("ascii").ljust(NAME_BYTES, b"\0")
    return tuple(float(int.from_bytes(data[i:i + _BYTES_PER_PARAM], "big"))
                 for i in range(0, NAME_BYTES, _BYTES_PER_PARAM))


def name_from_params(params: Sequence[float]) -> str | None:
    """The name seven parameters carry; None if they carry none validly (NaN reads 0)."""
    data = bytearray()
    for value in params:
        value = 0.0 if math.isnan(value) else value
        if not (math.isfinite(value) and value == int(value) and 0 <= value < 2**24):
            return None
        data += int(value).to_bytes(_BYTES_PER_PARAM, "big")
    text = bytes(data).rstrip(b"\0")
    if b"\0" in text or not all(0x20 <= b < 0x7F for b in text):
        return None
    return text.decode("ascii")
