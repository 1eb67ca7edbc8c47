"""``vmnav ground memory list|get``: the robot's visual paths and key image thumbnails over
MAVLink FTP.

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
    memory_sub.add_parser("list", help="the visual paths and their key images").set_defaults(
        action=run_list)
    get = memory_sub.add_parser("get", help="download key image thumbnails (PNG)")
    get.add_argument("ids", type=KEY_IMAGE, nargs="+", metavar="ID", help="key image ids")
    get.add_argument("--out", type=Path, required=True, metavar="DIR", help="folder to write to")
    get.set_defaults(action=run_get)


def run_list(station: GroundStation, args: argparse.Namespace) -> int:
    """Print a line per visual path of the robot's memory: id, name, its key images (the
    goals ``goto`` takes) and its length; the totals on stderr."""
    from ground.memory_index import MANIFEST_PATH, memory_index_from_manifest

    index = memory_index_from_manifest(station.ftp_get(MANIFEST_PATH))
    for path in index.paths:
        ids = path["keyframe_ids"]
        length_m = index.keyframes[ids[-1]]["distance_m"] if ids else 0.0
        print(f"path {path['id']} {path['name']!r}: key images {id_ranges(ids)} "
              f"({len(ids)}, {length_m:.2f} m)")
    print(f"paths: {len(index.paths)}, key images: {len(index.keyframes)}", file=sys.stderr)
    return 0


def id_ranges(ids: list[int]) -> str:
    """Key image ids in runs, e.g. ``[0, 1, 2, 5, 7, 8]`` -> ``"0-2, 5, 7-8"``."""
    runs: list[list[int]] = []
    for key in ids:
        if runs and key == runs[-1][-1] + 1:
            runs[-1].append(key)
        else:
            runs.append([key])
    return ", ".join(f"{run[0]}-{run[-1]}" if len(run) > 1 else f"{run[0]}" for run in runs)


def run_get(station: GroundStation, args: argparse.Namespace) -> int:
    """Download the thumbnails of ``args.ids`` into ``args.out``."""
    from shared.atomic_file import write_bytes_atomic

    args.out.mkdir(parents=True, exist_ok=True)
    for key in args.ids:
        path = args.out / f"{key}.png"
        write_bytes_atomic(path, station.ftp_get(f"{THUMBNAILS}/{key}.png"))
        print(path)
    return 0
