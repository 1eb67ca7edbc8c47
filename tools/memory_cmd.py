"""``vmnav memory ...``: inspect a visual memory on disk, or build a path from a teach log.

Each subcommand is a pair of functions here, ``add_<name>_parser(memory_sub)``
and ``run_<name>(args)``; :data:`SUBCOMMANDS` lists the parser builders, so a new
subcommand is one more pair and one more entry.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    from shared.memory import VisualMemory


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory`` and its subcommands."""
    memory = subparsers.add_parser("memory", help="inspect a visual memory")
    memory_sub = memory.add_subparsers(dest="memory_command", metavar="SUBCOMMAND", required=True)
    for add_subcommand in SUBCOMMANDS:
        add_subcommand(memory_sub)


def add_info_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory info DIR``."""
    info = memory_sub.add_parser(
        "info",
        help="paths, key images, spacing, junctions and connectivity of a memory",
        description="Read and validate the visual memory in DIR and print its paths (key "
        "images, length, key image spacing), its junctions and whether it is strongly "
        "connected, naming the key images that are not.",
    )
    info.add_argument("directory", type=Path, metavar="DIR", help="the memory's folder")
    info.add_argument("--json", action="store_true", help="print the summary as JSON")
    info.set_defaults(run=run_info)


def run_info(args: argparse.Namespace) -> int:
    """Print the summary of the memory in ``args.directory``."""
    from shared.memory import memory_summary, read_memory, summary_text

    summary = memory_summary(read_memory(args.directory))
    print(json.dumps(summary, indent=2) if args.json else summary_text(summary))
    return 0


def add_localize_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory localize DIR IMAGE.png``."""
    localize = memory_sub.add_parser(
        "localize",
        help="the key image of a memory that an image shows, its matches and the time taken",
        description="Localize IMAGE (a grey or colour 8-bit image of the memory camera's size) "
        "in the visual memory in DIR: a global prefilter over every key image, then Harris + "
        "ZNCC matching on the best candidates; the key image with the most matches wins "
        "(Courbon et al. 2008, sec. II-D). Prints it, its match count and the time taken.",
    )
    localize.add_argument("directory", type=Path, metavar="DIR", help="the memory's folder")
    localize.add_argument("image", type=Path, metavar="IMAGE", help="the query image (PNG, ...)")
    localize.add_argument(
        "--config", metavar="FILE", help="vmnav TOML config ([features], [localize] tables)"
    )
    localize.add_argument(
        "--exhaustive",
        action="store_true",
        help="also match every key image (the paper's rule, the baseline) and time it",
    )
    localize.add_argument("--json", action="store_true", help="print the result as JSON")
    localize.set_defaults(run=run_localize)


def run_localize(args: argparse.Namespace) -> int:
    """Print where ``args.image`` is in the memory in ``args.directory``."""
    import time

    from robot.config import load_config
    from robot.memory import Localizer
    from shared.memory import read_memory

    config = load_config(args.config)
    memory = read_memory(args.directory)
    image = read_query_image(args.image, memory.camera.width, memory.camera.height)
    t0 = time.perf_counter()
    localizer = Localizer.from_memory(memory, config.features, config.localize)
    t1 = time.perf_counter()
    result = localizer.localize(image)
    t2 = time.perf_counter()
    report: dict[str, object] = {
        "keyframe_id": result.keyframe_id,
        "matches": result.matches,
        "ok": result.ok,
        "localize_ms": round((t2 - t1) * 1e3, 2),
        "build_ms": round((t1 - t0) * 1e3, 2),
        "keyframes": len(memory.keyframes),
        "query_features": result.query_features,
        "candidates": [
            {"keyframe_id": c.keyframe_id, "similarity": round(c.similarity, 4),
             "matches": c.matches}
            for c in result.candidates
        ],
    }
    if args.exhaustive:
        t3 = time.perf_counter()
        baseline = localizer.localize_exhaustive(image)
        report["exhaustive"] = {
            "keyframe_id": baseline.keyframe_id,
            "matches": baseline.matches,
            "localize_ms": round((time.perf_counter() - t3) * 1e3, 2),
        }
    print(json.dumps(report, indent=2) if args.json else localize_text(memory, report))
    return 0


def read_query_image(path: Path, width: int, height: int) -> npt.NDArray[np.uint8]:
    """An 8-bit image file as a grey (height, width) array (colour is converted to grey).

    Raises:
        InputError: the file is missing, unreadable, not an 8-bit image or not
            ``width`` x ``height`` px.
    """
    import cv2
    import numpy as np

    from shared.errors import InputError

    if not path.is_file():
        raise InputError(path, "no such image file")
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None or image.size == 0:
        raise InputError(path, "cannot be decoded as an image")
    if image.dtype != np.uint8:
        raise InputError(path, f"expected 8-bit pixels, got {image.dtype}")
    if image.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        image = cv2.cvtColor(image, code)
    if image.shape != (height, width):
        raise InputError(
            path,
            f"is {image.shape[1]}x{image.shape[0]} px; the memory's camera takes "
            f"{width}x{height} px",
        )
    return image


def localize_text(memory: VisualMemory, report: dict[str, Any]) -> str:
    """The human-readable form of :func:`run_localize`'s report."""
    keyframe_id = report["keyframe_id"]
    if keyframe_id is None:
        return "the memory has no key images"
    keyframe = memory.keyframes[keyframe_id]
    path = memory.paths[keyframe.path_id]
    verdict = "" if report["ok"] else " (too few matches: not localized)"
    lines = [
        f"key image {keyframe_id} (path {path.id} {path.name!r}, index {keyframe.index}, "
        f"{keyframe.distance_m:.2f} m along): {report['matches']} matches{verdict}",
        f"  {report['localize_ms']:.1f} ms for {report['keyframes']} key images "
        f"({len(report['candidates'])} verified; localizer built in {report['build_ms']:.1f} ms)",
    ]
    if "exhaustive" in report:
        e = report["exhaustive"]
        lines.append(
            f"  exhaustive (every key image): key image {e['keyframe_id']} with {e['matches']} "
            f"matches in {e['localize_ms']:.1f} ms"
        )
    return "\n".join(lines)


def add_route_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory route DIR START GOAL``."""
    route = memory_sub.add_parser(
        "route",
        help="plan the visual route from one key image to a goal key image",
        description="Plan the shortest visual route (by teach odometric distance) through the "
        "memory's paths and junctions from key image START to key image GOAL, and list it.",
    )
    route.add_argument("directory", type=Path, metavar="DIR", help="the memory's folder")
    route.add_argument("start", type=int, metavar="START", help="id of the key image to start from")
    route.add_argument("goal", type=int, metavar="GOAL", help="id of the goal key image")
    route.add_argument("--json", action="store_true", help="print the route as JSON")
    route.set_defaults(run=run_route)


def run_route(args: argparse.Namespace) -> int:
    """Print the planned route; exit 1 when the goal cannot be reached."""
    from shared.errors import InputError
    from shared.memory import read_memory

    memory = read_memory(args.directory)
    walk = memory.plan_route(args.start, args.goal)
    if not walk:
        raise InputError(
            args.directory,
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
        "--camera",
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
    from tools.memory_build import build_path, summary_text

    config = load_config(args.config)
    name = args.log[0].stem if args.name is None else args.name
    built, memory = build_path(args.log, args.memory, name, args.camera, config)
    print(summary_text(built, memory, args.memory))
    return 0


SUBCOMMANDS = (add_info_parser, add_localize_parser, add_route_parser, add_build_parser)
