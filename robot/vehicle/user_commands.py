"""The vehicle's handlers of its own commands (numbers and name encoding:
:mod:`shared.mavlink.commands.user`): go to an uploaded photo, start and stop teaching.

Results: ACCEPTED when the robot took the request, DENIED when it cannot now or a
parameter is malformed (a STATUSTEXT after the ACK says why). Progress shows in the
telemetry (HEARTBEAT mode, MISSION_CURRENT, VISUAL_SERVO_STATUS, STATUSTEXT).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

from robot.vehicle.app_port import VehicleApp
from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP, name_from_params
from shared.mavlink.commands.vehicle import CommandReply, CommandRequest, Handler
from shared.mavlink.dialect import Message, mavlink

_MAX_PHOTO_ID = 2**24


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
