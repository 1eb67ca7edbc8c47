"""``vmnav vision localize IMG --memory DIR``: why an image does (or does not) localize.

For a user whose robot will not localize somewhere: every candidate the prefilter
picked is matched *and verified* (not only those that could still win), and the
JSON lists them best first with their scores (thumbnail similarity, matches,
verified inliers, inlier ratio, the fitted yaw and tilt) and each one's verdict,
then the overall verdict (:mod:`robot.memory.verification` says what each means).

Registered under ``vmnav vision`` by :mod:`tools.vision_cmd`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(vision_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav vision localize IMG --memory DIR``."""
    localize = vision_sub.add_parser(
        "localize",
        help="localize an image in a memory: the ranked key images with their scores "
             "(matches, verified inliers, ratio) and the verdict, as JSON",
        description="Localize IMG (an 8-bit grey or colour image of the memory camera's size) "
        "in the visual memory in DIR as the robot does: the prefilter's best candidates are "
        "matched, and each is verified geometrically (a relative pose on the sphere: enough "
        "inliers, a high enough share of inliers, a turn and a tilt a ground robot can make). "
        "Prints JSON: every candidate best first with its scores and verdict, the key image "
        "found and the verdict (ok: localized).",
    )
    localize.add_argument("image", type=Path, metavar="IMG", help="the query image (PNG, JPEG)")
    localize.add_argument("--memory", type=Path, required=True, metavar="DIR",
                          help="the memory's folder")
    localize.add_argument("--config", metavar="FILE",
                          help="vmnav TOML config ([features], [localize], [camera.mount])")
    localize.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the localization of ``args.image`` in ``args.memory`` as JSON."""
    import time

    from robot.config import load_config
    from robot.memory import Localizer
    from robot.memory.localize_report import localization_json, read_query_image
    from shared.memory import read_memory

    config = load_config(args.config)
    memory = read_memory(args.memory)
    image = read_query_image(args.image, memory.camera.width, memory.camera.height)
    localizer = Localizer.from_memory(memory, config.camera.mount, config.features,
                                      config.localize)
    t0 = time.perf_counter()
    result = localizer.localize(image, verify_all=True)
    report = {
        "image": str(args.image),
        "memory": str(args.memory),
        "keyframes": len(memory.keyframes),
        **localization_json(memory, result),
        "localize_ms": round((time.perf_counter() - t0) * 1e3, 2),
    }
    print(json.dumps(report, indent=2))
    return 0
