"""``vmnav memory localize --memory DIR IMAGE``: the key image of a memory that an image shows.

Registered under ``vmnav memory`` by :mod:`tools.memory_cmd`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from shared.memory import VisualMemory


def add_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory localize --memory DIR IMAGE.png``."""
    localize = memory_sub.add_parser(
        "localize",
        help="the key image of a memory that an image shows, its scores and the time taken",
        description="Localize IMAGE (a grey or colour 8-bit image of the memory camera's size) "
        "in the visual memory in DIR: a global prefilter over every key image, then Harris + "
        "ZNCC matching and a relative pose on the best candidates; the key image verified "
        "with the most inliers wins. Prints it, its matches and inliers and the time taken.",
    )
    localize.add_argument("--memory", required=True, type=Path, metavar="DIR",
                      help="the memory's folder")
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
    """Print where ``args.image`` is in the memory in ``args.memory``."""
    import time

    from robot.config import load_config
    from robot.memory import Localizer
    from robot.memory.localize_report import localization_json, read_query_image
    from shared.memory import read_memory

    config = load_config(args.config)
    memory = read_memory(args.memory)
    image = read_query_image(args.image, memory.camera.width, memory.camera.height)
    t0 = time.perf_counter()
    localizer = Localizer.from_memory(memory, config.camera.mount, config.features,
                                      config.localize)
    t1 = time.perf_counter()
    result = localizer.localize(image)
    t2 = time.perf_counter()
    report: dict[str, Any] = {
        **localization_json(memory, result),
        "localize_ms": round((t2 - t1) * 1e3, 2),
        "build_ms": round((t1 - t0) * 1e3, 2),
        "keyframes": len(memory.keyframes),
    }
    if args.exhaustive:
        t3 = time.perf_counter()
        baseline = localizer.localize_exhaustive(image)
        report["exhaustive"] = {
            "keyframe_id": baseline.keyframe_id,
            "matches": baseline.matches,
            "inliers": baseline.inliers,
            "ok": baseline.ok,
            "localize_ms": round((time.perf_counter() - t3) * 1e3, 2),
        }
    print(json.dumps(report, indent=2) if args.json else localize_text(memory, report))
    return 0


def localize_text(memory: VisualMemory, report: dict[str, Any]) -> str:
    """The human-readable form of :func:`run_localize`'s report."""
    keyframe_id = report["keyframe_id"]
    if keyframe_id is None:
        return "the memory has no key images"
    keyframe = memory.keyframes[keyframe_id]
    path = memory.paths[keyframe.path_id]
    verdict = "" if report["ok"] else f" ({report['verdict']}: not localized)"
    verified = sum(c["verdict"] is not None for c in report["candidates"])
    lines = [
        f"key image {keyframe_id} (path {path.id} {path.name!r}, index {keyframe.index}, "
        f"{keyframe.distance_m:.2f} m along): {report['matches']} matches, "
        f"{report['inliers']} verified inliers{verdict}",
        f"  {report['localize_ms']:.1f} ms for {report['keyframes']} key images "
        f"({len(report['candidates'])} matched, {verified} verified; localizer built in "
        f"{report['build_ms']:.1f} ms)",
    ]
    if "exhaustive" in report:
        e = report["exhaustive"]
        lines.append(
            f"  exhaustive (every key image): key image {e['keyframe_id']} with {e['matches']} "
            f"matches, {e['inliers']} verified inliers in {e['localize_ms']:.1f} ms"
        )
    return "\n".join(lines)
