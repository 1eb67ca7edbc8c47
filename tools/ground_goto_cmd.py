"""``vmnav ground goto``: drive to a key image, or to where a photo was taken.

A key image goes as a one-item mission (MISSION_ITEM_INT upload, then MISSION_START); a
photo is uploaded over MAVLink FTP and the robot is asked to find it in its memory (a
long-running command: the answer names the key image found, or why not). ``--wait``
follows the run to its end, with the robot's servo state on a status line on a terminal;
exit code 0 when the goal was reached, 1 with the reason when not.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from tools.harness.arg_types import KEY_IMAGE, POSITIVE

if TYPE_CHECKING:
    from ground.station import GroundStation

#: Default wait for a goal to be reached (``goto --wait``), s.
DEFAULT_WAIT_S = 600.0
#: ``goto --wait`` refreshes its status line this often, s.
_PROGRESS_PERIOD_S = 0.5


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground goto``."""
    goto = ground_sub.add_parser("goto", help="drive to a key image, or to where a photo was taken",
                          description="Upload a one-goal mission and start it, or upload a "
                          "photo and ask the robot to localize it and go there.")
    goto.add_argument("goal_key", type=KEY_IMAGE, nargs="?", metavar="KEY",
                      help="goal key image id")
    goto.add_argument("--image", type=Path, metavar="PHOTO", help="goal photo (JPEG, PNG...)")
    goto.add_argument("--wait", action="store_true",
                      help="wait for the outcome; exit code 0 reached, 1 not")
    goto.add_argument("--wait-timeout", type=POSITIVE, default=DEFAULT_WAIT_S, metavar="S",
                      help=f"give up waiting after S seconds (default {DEFAULT_WAIT_S:g})")
    goto.set_defaults(action=run_goto, check=check_goto)


def check_goto(args: argparse.Namespace) -> None:
    """One goal, and a photo that reads and decodes (sets ``args.photo``, its bytes), before
    anything connects.

    Raises:
        InputError: no goal or two; a photo that cannot be read or is not a sound image.
    """
    from shared.errors import InputError
    from shared.image_decode import check_image

    if (args.goal_key is None) == (args.image is None):
        raise InputError("goto", "give either a key image id KEY or --image PHOTO")
    args.photo = None
    if args.image is not None:
        try:
            args.photo = args.image.read_bytes()
        except OSError as e:
            raise InputError(args.image, f"cannot read the goal photo: {e.strerror}") from None
        check_image(args.photo, args.image)  # refused here in one line rather than by the robot


def run_goto(station: GroundStation, args: argparse.Namespace) -> int:
    """Dispatch the goal (checked by :func:`check_goto`); with ``--wait``, 0 when reached and
    1 when not."""
    from ground.telemetry_text import not_reached_text
    from shared.errors import InputError
    from shared.mavlink.mission.goal import Goal

    vehicle = station.vehicle
    if args.image is not None:
        found = station.goto_photo(args.photo, args.image.suffix)
        print(f"vehicle {vehicle.system_id}: photo {args.image.name} (uploaded as photo "
              f"{found.photo_id}) found at key image {found.keyframe_id}; going there"
              + (f"\n  the robot: {found.said}" if found.said else ""))
    else:
        try:
            goal = Goal(args.goal_key)
        except ValueError as e:
            raise InputError("KEY", str(e)) from None
        station.upload_goals([goal])
        station.start_mission()
        print(f"vehicle {vehicle.system_id}: going to key image {args.goal_key}")
    if not args.wait:
        return 0
    if _wait_with_progress(station, args.wait_timeout):
        print(f"vehicle {vehicle.system_id}: goal reached")
        return 0
    why = not_reached_text(station.mission_outcome, args.wait_timeout, vehicle.notices)
    print(f"vmnav ground: goal not reached: {why}", file=sys.stderr)
    return 1


def _wait_with_progress(station: GroundStation, timeout_s: float) -> bool:
    """:meth:`GroundStation.wait_mission_done`, with the robot's servo state on a status
    line while it drives (on a terminal)."""
    from ground.telemetry_text import describe
    from tools.harness.progress import Progress

    vehicle = station.vehicle
    end_s = time.monotonic() + timeout_s
    with Progress(f"vehicle {vehicle.system_id}") as bar:
        while True:
            step_s = max(0.0, min(_PROGRESS_PERIOD_S, end_s - time.monotonic()))
            if station.wait_mission_done(step_s):
                return True
            if station.mission_outcome is not None or time.monotonic() >= end_s:
                return False
            servo = vehicle.telemetry.get("VISUAL_SERVO_STATUS")
            bar.update(detail=(describe(servo) or "") if servo is not None else "")
