"""The vehicle's handlers of its own commands (numbers and name encoding:
:mod:`shared.mavlink.commands.user`): go to an uploaded photo, start and stop teaching.

Results: ACCEPTED when the robot took the request, DENIED when it cannot now or a
parameter is malformed (a STATUSTEXT after the ACK says why). Progress shows in the
telemetry (HEARTBEAT mode, MISSION_CURRENT, VISUAL_SERVO_STATUS, STATUSTEXT).

Go to a photo and stop teaching are long-running commands (MAVLink's command
protocol, ``MAV_RESULT_IN_PROGRESS``): the application's worker takes a while to find
the photo in the memory, or to join and write the taught path, and either may fail
(:class:`JobCommands`):

1. Taken, the command is answered IN_PROGRESS (progress 255: unknown), and again
   every :data:`PROGRESS_PERIOD_NS` while the job runs, so that the ground station's
   command client neither resends nor gives up.
2. The job's outcome ends it with a final COMMAND_ACK to the station that sent it:
   ACCEPTED with ``result_param2`` what the job made (the key image the photo was
   found at, now the goal; the id of the path stored), or FAILED with
   ``result_param2`` -1. The application's notice of the outcome (the key image and
   its scores, the path's key images, or why not: a STATUSTEXT) goes before it.
3. One job of a kind at a time: another GOTO_PHOTO while a photo is looked up is DENIED.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

from robot.vehicle.app_port import Job, JobOutcome, VehicleApp
from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.mavlink.address import Address
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP, name_from_params
from shared.mavlink.commands.vehicle import CommandReply, CommandRequest, Handler
from shared.mavlink.dialect import Message, mavlink

_MAX_PHOTO_ID = 2**24
#: While a job runs, its command is answered IN_PROGRESS this often, ns (rule 1; the
#: ground's client waits 1 s after the last ACK: ``shared.mavlink.commands.gcs``).
PROGRESS_PERIOD_NS = 400_000_000
#: COMMAND_ACK ``progress`` of an IN_PROGRESS answer: unknown.
_PROGRESS_UNKNOWN = 255
#: The command each job answers.
_JOB_COMMANDS: dict[Job, int] = {"photo": GOTO_PHOTO, "path": TEACH_STOP}


class JobCommands:
    """The commands waiting for their job's outcome (module rules 1-3), sans-I/O."""

    def __init__(self) -> None:
        self._waiting: dict[Job, Address] = {}
        self._due_ns: int | None = None

    def busy(self, job: Job) -> bool:
        """A command waits for ``job``."""
        return job in self._waiting

    def start(self, job: Job, source: Address, now_ns: int) -> CommandReply:
        """``job``'s command was taken from ``source``: answer IN_PROGRESS, and keep
        answering (rule 1)."""
        self._waiting[job] = source
        self._due_ns = now_ns + PROGRESS_PERIOD_NS
        return CommandReply(mavlink.MAV_RESULT_IN_PROGRESS, progress=_PROGRESS_UNKNOWN)

    def get_timer(self) -> int | None:
        """When the next IN_PROGRESS answers are due, ns; None when none waits."""
        return self._due_ns

    def progress(self, now_ns: int) -> list[Message]:
        """The IN_PROGRESS answers when due (rule 1)."""
        if self._due_ns is None or now_ns < self._due_ns:
            return []
        self._due_ns = now_ns + PROGRESS_PERIOD_NS
        return [_ack(job, source, mavlink.MAV_RESULT_IN_PROGRESS, _PROGRESS_UNKNOWN, 0)
                for job, source in self._waiting.items()]

    def finish(self, outcome: JobOutcome) -> list[Message]:
        """The final answer (rule 2); nothing when no command waits for the job."""
        source = self._waiting.pop(outcome.job, None)
        if not self._waiting:
            self._due_ns = None
        if source is None:
            return []
        if outcome.value is None:
            return [_ack(outcome.job, source, mavlink.MAV_RESULT_FAILED, 0, -1)]
        return [_ack(outcome.job, source, mavlink.MAV_RESULT_ACCEPTED, 100, outcome.value)]


def _ack(job: Job, to: Address, result: int, progress: int, result_param2: int) -> Message:
    return mavlink.MAVLink_command_ack_message(
        _JOB_COMMANDS[job], result, progress, result_param2,
        target_system=to.system_id, target_component=to.component_id)


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
                  notice: Callable[[str], list[Message]], jobs: JobCommands,
                  now_ns: Callable[[], int]) -> dict[int, Handler]:
    """The handlers of the three user commands.

    Args:
        app: the application they drive.
        fs: the served files, to find uploaded photos.
        notice: makes the STATUSTEXT explaining a refusal.
        jobs: the commands waiting for their job (module rules).
        now_ns: the endpoint's time now, ns.
    """

    def result(ok: bool, refusal: str) -> CommandReply:
        if ok:
            return CommandReply(mavlink.MAV_RESULT_ACCEPTED)
        return CommandReply(mavlink.MAV_RESULT_DENIED, tuple(notice(refusal)))

    def goto_photo(r: CommandRequest) -> CommandReply:
        if jobs.busy("photo"):
            return result(False, "go to photo: another photo is being looked up")
        path = find_photo(fs, r.params[0])
        if isinstance(path, str):
            return result(False, f"go to photo: {path}")
        if not app.goto_image(path):
            return result(False, f"go to photo: {path.name} refused now")
        return jobs.start("photo", r.source, now_ns())

    def teach_start(r: CommandRequest) -> CommandReply:
        name = name_from_params(r.params)
        if name is None:
            return result(False, "teach start: parameters carry no valid path name")
        return result(app.teach_start(name), f"teach start {name!r}: refused now")

    def teach_stop(r: CommandRequest) -> CommandReply:
        if not app.teach_stop():
            return result(False, "teach stop: not teaching")
        return jobs.start("path", r.source, now_ns())

    return {
        GOTO_PHOTO: goto_photo,
        TEACH_START: teach_start,
        TEACH_STOP: teach_stop,
    }
