"""The robot's own commands, in common.xml's user range (reference/mavlink-vehicle.md
sec. 0.4 and 5): every ground station can send them by number (MAVProxy ``long 31010 7``,
MAVSDK ``MavlinkDirect.send_command``), as COMMAND_LONG or COMMAND_INT.

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
telemetry (HEARTBEAT mode, MISSION_CURRENT, VISUAL_SERVO_STATUS, STATUSTEXT).

Name encoding: up to :data:`NAME_BYTES` printable ASCII bytes, 3 per parameter in
order, each parameter the big-endian integer of its 3 bytes (0..2^24-1, exact in a
float32 and in COMMAND_INT's int32 x/y), zero-padded at the end.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path

from robot.vehicle.app_port import VehicleApp
from shared.mavlink.commands import CommandReply, CommandRequest, Handler
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.ftp_memory import MemoryFileSystem

GOTO_PHOTO = mavlink.MAV_CMD_USER_1
TEACH_START = mavlink.MAV_CMD_USER_2
TEACH_STOP = mavlink.MAV_CMD_USER_3

#: Longest path name a TEACH_START carries, bytes.
NAME_BYTES = 21
_BYTES_PER_PARAM = 3
_MAX_PHOTO_ID = 2**24


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


def find_photo(fs: MemoryFileSystem, photo_id: float) -> Path | str:
    """The local path of uploaded photo ``photo_id``, or why there is none.

    Args:
        fs: the served files (its ``/upload`` area).
        photo_id: GOTO_PHOTO's param1.
    """
    if not (math.isfinite(photo_id) and photo_id == int(photo_id)
            and 1 <= photo_id <= _MAX_PHOTO_ID):
        return f"photo id {photo_id} is not an integer in 1..{_MAX_PHOTO_ID}"
    stem = str(int(photo_id))
    names = [e.name for e in fs.list_directory("/upload")
             if not e.is_dir and e.name.rpartition(".")[0] == stem]
    if len(names) != 1:
        found = "none" if not names else ", ".join(names)
        return f"want one uploaded /upload/{stem}.<ext>, found {found}"
    return fs.upload_dir / names[0]


def user_handlers(app: VehicleApp, fs: MemoryFileSystem,
                  notice: Callable[[str], list[Message]]) -> dict[int, Handler]:
    """The handlers of the three user commands.

    Args:
        app: the application they drive.
        fs: the served files, to find uploaded photos.
        notice: makes the STATUSTEXT explaining a refusal.
    """

    def result(ok: bool, refusal: str) -> CommandReply:
        if ok:
            return CommandReply(mavlink.MAV_RESULT_ACCEPTED)
        return CommandReply(mavlink.MAV_RESULT_DENIED, tuple(notice(refusal)))

    def goto_photo(r: CommandRequest) -> CommandReply:
        photo = find_photo(fs, r.params[0])
        if isinstance(photo, str):
            return result(False, f"go to photo: {photo}")
        return result(app.goto_image(photo), f"go to photo: {photo.name} refused now")

    def teach_start(r: CommandRequest) -> CommandReply:
        name = name_from_params(r.params)
        if name is None:
            return result(False, "teach start: parameters carry no valid path name")
        return result(app.teach_start(name), f"teach start {name!r}: refused now")

    return {
        GOTO_PHOTO: goto_photo,
        TEACH_START: teach_start,
        TEACH_STOP: lambda r: result(app.teach_stop(), "teach stop: not teaching"),
    }
