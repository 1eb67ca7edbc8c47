"""``vmnav ground teach start NAME|stop``: record a visual path while the robot is driven.

Registered under ``vmnav ground`` by :mod:`tools.ground_cmd`, which connects and
calls the action with the station.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ground.station import GroundStation


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground teach start NAME`` and ``vmnav ground teach stop``."""
    teach = ground_sub.add_parser("teach", help="record a visual path while driving")
    teach_sub = teach.add_subparsers(dest="teach_command", metavar="ACTION", required=True)
    start = teach_sub.add_parser("start", help="start recording")
    start.add_argument("name", metavar="NAME", help="the path's name (up to 21 ASCII characters)")
    start.set_defaults(action=run_start, check=check_start)
    teach_sub.add_parser("stop", help="stop; the path joins the memory").set_defaults(
        action=run_stop)


def check_start(args: argparse.Namespace) -> None:
    """The path's name fits a TEACH_START, before anything connects.

    Raises:
        InputError: not up to 21 printable ASCII characters.
    """
    from shared.errors import InputError
    from shared.mavlink.commands.user import params_from_name

    try:
        params_from_name(args.name)
    except ValueError as e:
        raise InputError("NAME", str(e)) from None


def run_start(station: GroundStation, args: argparse.Namespace) -> int:
    """Start recording path ``args.name``."""
    station.teach_start(args.name)
    print(f"vehicle {station.vehicle.system_id}: teaching {args.name!r}")
    return 0


def run_stop(station: GroundStation, args: argparse.Namespace) -> int:
    """Stop recording."""
    stored = station.teach_stop()
    print(f"vehicle {station.vehicle.system_id}: teaching stopped, path {stored.path_id} stored"
          + (f"\n  the robot: {stored.said}" if stored.said else ""))
    return 0
