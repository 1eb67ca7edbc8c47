"""``vmnav ground memory list|get``: the robot's key image thumbnails over MAVLink FTP.

Registered under ``vmnav ground`` by :mod:`tools.ground_cmd`, which connects and
calls the action with the station.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from tools.harness.arg_types import KEY_IMAGE

if TYPE_CHECKING:
    from ground.station import GroundStation

#: Where the robot serves its key image thumbnails (``robot.vehicle.ftp_memory``).
THUMBNAILS = "/memory/thumbnails"


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground memory list`` and ``vmnav ground memory get ID... --out DIR``."""
    memory = ground_sub.add_parser("memory", help="the robot's visual memory over MAVLink FTP")
    memory_sub = memory.add_subparsers(dest="memory_command", metavar="ACTION", required=True)
    memory_sub.add_parser("list", help="key images with a thumbnail").set_defaults(
        action=run_list)
    get = memory_sub.add_parser("get", help="download key image thumbnails (PNG)")
    get.add_argument("ids", type=KEY_IMAGE, nargs="+", metavar="ID", help="key image ids")
    get.add_argument("--out", type=Path, required=True, metavar="DIR", help="folder to write to")
    get.set_defaults(action=run_get)


def run_list(station: GroundStation, args: argparse.Namespace) -> int:
    """Print the key image ids that have a thumbnail, one per line with its size."""
    entries = station.ftp_list(THUMBNAILS)
    ids = sorted(int(e.name.removesuffix(".png")) for e in entries
                 if not e.is_dir and e.name.removesuffix(".png").isdigit())
    sizes = {e.name: e.size for e in entries}
    for key in ids:
        print(f"{key}\t{sizes[f'{key}.png']} bytes")
    print(f"{len(ids)} key images", file=sys.stderr)
    return 0


def run_get(station: GroundStation, args: argparse.Namespace) -> int:
    """Download the thumbnails of ``args.ids`` into ``args.out``."""
    from shared.atomic_file import write_bytes_atomic

    args.out.mkdir(parents=True, exist_ok=True)
    for key in args.ids:
        path = args.out / f"{key}.png"
        write_bytes_atomic(path, station.ftp_get(f"{THUMBNAILS}/{key}.png"))
        print(path)
    return 0
