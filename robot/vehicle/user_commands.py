"""The vehicle's handlers of its own commands (numbers and name encoding:
:mod:`shared.mavlink.commands.user`): go to an uploaded photo, start and stop teaching.

Results: ACCEPTED when the robot took the request, DENIED when it cannot now or a
parameter is malformed (a STATUSTEXT after the ACK says why). Progress shows in the
telemetry (HEARTBEAT mode, MISSION_CURRENT, VISUAL_SERVO_STATUS, STATUSTEXT).

Go to a photo is a long-running command (MAVLink's command protocol,
``MAV_RESULT_IN_PROGRESS``), because finding the photo in the memory takes the worker
a while and may fail (:class:`PhotoCommand`):

1. Taken, it is answered IN_PROGRESS (progress 255: unknown), and again every
   :data:`PROGRESS_PERIOD_NS` while the photo is looked up, so that the ground
   station's command client neither resends nor gives up.
2. The outcome ends it with a final COMMAND_ACK to the station that sent it:
   ACCEPTED with ``result_param2`` the key image the photo was found at (the goal
   now), or FAILED with ``result_param2`` -1. The application's notice of the outcome
   (the key image and its score, or why not: a STATUSTEXT) goes before it.
3. One photo at a time: another GOTO_PHOTO while one is looked up is DENIED.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

from robot.vehicle.app_port import PhotoOutcome, VehicleApp
from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.mavlink.address import Address
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP, name_from_params
from shared.mavlink.commands.vehicle import CommandReply, CommandRequest, Handler
from shared.mavlink.dialect import Message, mavlink

_MAX_PHOTO_ID = 2**24
#: While a photo is looked up, GOTO_PHOTO is answered IN_PROGRESS this often, ns (rule 1;
#: the ground's client waits 1 s after the last ACK: ``shared.mavlink.commands.gcs``).
PROGRESS_PERIOD_NS = 400_000_000
#: COMMAND_ACK ``progress`` of an IN_PROGRESS answer: unknown.
_PROGRESS_UNKNOWN = 255


class PhotoCommand:
    """The GOTO_PHOTO being looked up, if any (module rules 1-3), sans-I/O."""

    def __init__(self) -> None:
        self._source: Address | None = None
        self._due_ns: int | None = None

    @property
    def busy(self) -> bool:
        """A photo is being looked up."""
        return self._source is not None

    def start(self, source: Address, now_ns: int) -> CommandReply:
        """The command was taken: answer IN_PROGRESS, and keep answering (rule 1)."""
        self._source, self._due_ns = source, now_ns + PROGRESS_PERIOD_NS
        return CommandReply(mavlink.MAV_RESULT_IN_PROGRESS, progress=_PROGRESS_UNKNOWN)

    def get_timer(self) -> int | None:
        """When the next IN_PROGRESS answer is due, ns; None when idle."""
        return self._due_ns

    def progress(self, now_ns: int) -> list[Message]:
        """The IN_PROGRESS answer when due (rule 1)."""
        if self._source is None or self._due_ns is None or now_ns < self._due_ns:
            return []
        self._due_ns = now_ns + PROGRESS_PERIOD_NS
        return [self._ack(mavlink.MAV_RESULT_IN_PROGRESS, _PROGRESS_UNKNOWN, 0)]

    def finish(self, outcome: PhotoOutcome) -> list[Message]:
        """The final answer (rule 2); nothing when no command waits."""
        if self._source is None:
            return []
        ack = (self._ack(mavlink.MAV_RESULT_FAILED, 0, -1) if outcome.keyframe_id is None
               else self._ack(mavlink.MAV_RESULT_ACCEPTED, 100, outcome.keyframe_id))
        self._source = self._due_ns = None
        return [ack]

    def _ack(self, result: int, progress: int, result_param2: int) -> Message:
        assert self._source is not None
        return mavlink.MAVLink_command_ack_message(
            GOTO_PHOTO, result, progress, result_param2,
            target_system=self._source.system_id, target_component=self._source.component_id)


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
                  notice: Callable[[str], list[Message]], photo: PhotoCommand,
                  now_ns: Callable[[], int]) -> dict[int, Handler]:
    """The handlers of the three user commands.

    Args:
        app: the application they drive.
        fs: the served files, to find uploaded photos.
        notice: makes the STATUSTEXT explaining a refusal.
        photo: the photo being looked up (module rules).
        now_ns: the endpoint's time now, ns.
    """

    def result(ok: bool, refusal: str) -> CommandReply:
        if ok:
            return CommandReply(mavlink.MAV_RESULT_ACCEPTED)
        return CommandReply(mavlink.MAV_RESULT_DENIED, tuple(notice(refusal)))

    def goto_photo(r: CommandRequest) -> CommandReply:
        if photo.busy:
            return result(False, "go to photo: another photo is being looked up")
        path = find_photo(fs, r.params[0])
        if isinstance(path, str):
            return result(False, f"go to photo: {path}")
        if not app.goto_image(path):
            return result(False, f"go to photo: {path.name} refused now")
        return photo.start(r.source, now_ns())

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
