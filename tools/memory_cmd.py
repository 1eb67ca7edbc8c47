"""``vmnav memory ...``: inspect a visual memory on disk, or build a path from a teach log.

Each subcommand is a pair of functions here, ``add_<name>_parser(memory_sub)``
and ``run_<name>(args)``, or a module of its own (``vmnav memory localize``:
:mod:`tools.memory_localize_cmd`); :data:`SUBCOMMANDS` lists the parser builders, so a
new subcommand is one more pair and one more entry.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

from tools import memory_localize_cmd
from tools.harness.arg_types import KEY_IMAGE


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory`` and its subcommands."""
    memory = subparsers.add_parser("memory", help="inspect a visual memory")
    memory_sub = memory.add_subparsers(dest="memory_command", metavar="SUBCOMMAND", required=True)
    for add_subcommand in SUBCOMMANDS:
        add_subcommand(memory_sub)


def add_info_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory info --memory DIR``."""
    info = memory_sub.add_parser(
        "info",
        help="paths, key images, spacing, junctions and connectivity of a memory",
        description="Read and validate the visual memory in DIR and print its paths (key "
        "images, length, key image spacing), its junctions and whether it is strongly "
        "connected, naming the key images that are not.",
    )
    info.add_argument("--memory", required=True, type=Path, metavar="DIR",
                      help="the memory's folder")
    info.add_argument("--json", action="store_true", help="print the summary as JSON")
    info.set_defaults(run=run_info)


def run_info(args: argparse.Namespace) -> int:
    """Print the summary of the memory in ``args.memory``."""
    from shared.memory import memory_summary, read_memory, summary_text

    summary = memory_summary(read_memory(args.memory))
    print(json.dumps(summary, indent=2) if args.json else summary_text(summary))
    return 0


def add_route_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory route --memory DIR START GOAL``."""
    route = memory_sub.add_parser(
        "route",
        help="plan the visual route from one key image to a goal key image",
        description="Plan the shortest visual route (by teach odometric distance) through the "
        "memory's paths and junctions from key image START to key image GOAL, and list it.",
    )
    route.add_argument("--memory", required=True, type=Path, metavar="DIR",
                      help="the memory's folder")
    route.add_argument("start", type=KEY_IMAGE, metavar="START",
                       help="id of the key image to start from")
    route.add_argument("goal", type=KEY_IMAGE, metavar="GOAL", help="id of the goal key image")
    route.add_argument("--json", action="store_true", help="print the route as JSON")
    route.set_defaults(run=run_route)


def run_route(args: argparse.Namespace) -> int:
    """Print the planned route; exit 1 when the goal cannot be reached."""
    from shared.errors import InputError
    from shared.memory import read_memory

    memory = read_memory(args.memory)
    walk = memory.plan_route(args.start, args.goal)
    if not walk:
        raise InputError(
            args.memory,
            f"key image {args.goal} cannot be reached from key image {args.start} "
            "(see 'vmnav memory info' for the memory's connectivity)",
        )
    steps = list(itertools.pairwise(walk))
    lengths = {(e.from_id, e.to_id): e for e in memory.edges()}
    length_m = sum(lengths[s].length_m for s in steps)
    junctions = sum(1 for s in steps if lengths[s].kind.name == "JUNCTION")
    path_names = []
    for kf in walk:
        name = memory.paths[memory.keyframes[kf].path_id].name
        if not path_names or path_names[-1] != name:
            path_names.append(name)
    report = {
        "start": args.start,
        "goal": args.goal,
        "keyframe_ids": walk,
        "length_m": round(length_m, 3),
        "junctions": junctions,
        "paths": path_names,
    }
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(
            f"route from key image {args.start} to {args.goal}: {len(walk)} key images, "
            f"{length_m:.2f} m, {junctions} junction(s), along {' -> '.join(path_names)}"
        )
        print("  " + " ".join(str(k) for k in walk))
    return 0


def add_build_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory build LOG.mcap [LOG ...] --memory DIR``."""
    build = memory_sub.add_parser(
        "build",
        help="build a visual path from a recorded teach drive (an MCAP log)",
        description="Select key images from the camera frames and odometry of a teach drive "
        "recorded in LOG (a robot field log, or 'vmnav teach --sim --log'), add them as a new "
        "path to the visual memory in DIR (created if needed) and join it to the paths already "
        "there where its ends are localized. A log rotated into several files is given as its "
        "files, or as its first file (NAME-0001.mcap stands for the files of the same run "
        "numbered after it).",
    )
    build.add_argument("log", type=Path, nargs="+", metavar="LOG",
                       help="the teach log (MCAP): its files, or the first of a series")
    build.add_argument(
        "--memory", required=True, type=Path, metavar="DIR", help="the visual memory's folder"
    )
    build.add_argument("--name",
                       help="the new path's name [default: the (first) log file's stem]")
    build.add_argument(
        "--calibration",
        metavar="FILE",
        help="camera calibration JSON of a new memory; must match an existing memory's "
        "[default: the memory's camera, or 800x600, 185 deg]",
    )
    build.add_argument(
        "--config", metavar="FILE", help="vmnav TOML config ([features], [teach], [localize])"
    )
    build.set_defaults(run=run_build)


def run_build(args: argparse.Namespace) -> int:
    """Build a path of the memory in ``args.memory`` from ``args.log``; print a summary."""
    from robot.config import load_config
    from robot.memory.path_from_log import build_path, summary_text

    config = load_config(args.config)
    name = args.log[0].stem if args.name is None else args.name
    built, memory = build_path(args.log, args.memory, name, args.calibration, config)
    print(summary_text(built, memory, args.memory))
    return 0


SUBCOMMANDS = (add_info_parser, memory_localize_cmd.add_parser, add_route_parser,
               add_build_parser)
