"""``vmnav vision pair IMG_A IMG_B --calibration CAM_A``: two images' matches and relative pose.

Prints JSON: the corners found in each image, the matches, the inliers of the relative
pose, the pose (``rotation_vector_deg``, ``rotation_deg``, the unit
``translation_direction``, with ``X_b = R X_a + t``: OpenCV's stereo convention) and the
time the front end and the pose took; ``--out FILE.png`` draws the matches and inliers
(:mod:`tools.figures.pair_matches`). Registered under ``vmnav vision`` by
:mod:`tools.vision_cmd`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from tools.harness.arg_types import SEED


def add_parser(vision_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav vision pair``."""
    pair = vision_sub.add_parser(
        "pair",
        help="match two images and fit their relative pose; JSON, optional picture",
        description="Find corners in IMG_A and IMG_B, match them, lift the matches to "
        "bearings through each image's calibration and fit the general relative pose "
        "(5-point RANSAC on the sphere, inlier tolerance an angle). Prints JSON with "
        "X_b = R X_a + t (a point's coordinates in camera a's frame to camera b's).",
    )
    pair.add_argument("image_a", type=Path, metavar="IMG_A", help="first image (PNG, JPEG, PGM...)")
    pair.add_argument("image_b", type=Path, metavar="IMG_B", help="second image")
    pair.add_argument("--calibration", required=True, type=Path, metavar="CAM_A",
                      help="vmnav calibration JSON of IMG_A's camera (vmnav calibrate)")
    pair.add_argument("--calibration-b", type=Path, metavar="CAM_B",
                      help="calibration of IMG_B's camera [default: CAM_A]")
    pair.add_argument("--out", type=Path, metavar="FILE.png",
                      help="write a picture of the inliers (green) and rejected matches (red); "
                           "JPEG if FILE ends in .jpg")
    pair.add_argument("--config", type=Path, metavar="FILE",
                      help="vmnav TOML config: the front end of its [features] table and the "
                           "matching of its [localize] table [default: the defaults]")
    pair.add_argument("--seed", type=SEED, default=0, help="seed of RANSAC's samples [default: 0]")
    pair.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the pair's JSON (and draw it); returns the exit code."""
    import time

    import numpy as np

    from robot.config import load_config
    from robot.vision.two_view import TwoViewConfig, rotation_vector_deg, two_cameras, two_view
    from shared.calibration import check_image_size, read_camera
    from shared.errors import InputError
    from shared.image_decode import FILE_FORMATS, read_grey

    config = load_config(args.config)
    camera_a = read_camera(args.calibration)
    camera_b = camera_a if args.calibration_b is None else read_camera(args.calibration_b)
    image_a = read_grey(args.image_a, error=InputError, formats=FILE_FORMATS)
    image_b = read_grey(args.image_b, error=InputError, formats=FILE_FORMATS)
    check_image_size(camera_a, image_a.shape[1], image_a.shape[0], args.calibration)
    check_image_size(camera_b, image_b.shape[1], image_b.shape[0],
                     args.calibration_b or args.calibration)
    cameras = two_cameras(camera_a, camera_b, config.features)
    start_ns = time.perf_counter_ns()
    result = two_view(image_a, image_b, cameras, TwoViewConfig(matching=config.localize.matching),
                      np.random.default_rng(args.seed))
    elapsed_ns = time.perf_counter_ns() - start_ns
    fit = result.fit
    report: dict[str, Any] = {
        "image_a": str(args.image_a),
        "image_b": str(args.image_b),
        "method": config.features.method,
        "corners_a": len(result.corners_a),
        "corners_b": len(result.corners_b),
        "matches": len(result.matched_a),
        "inliers": fit.n_inliers,
        "ok": fit.ok,
        "rotation_vector_deg": [round(float(x), 4) for x in rotation_vector_deg(fit.R_b_a)],
        "rotation_deg": round(float(np.linalg.norm(rotation_vector_deg(fit.R_b_a))), 4),
        "translation_direction": [round(float(x), 5) for x in fit.t_b_a],
        # Near 0 the views barely moved apart and the direction means little.
        "parallax_deg": round(float(np.degrees(fit.parallax_rad)), 3),
        "convention": "X_b = R X_a + t",
        "time_ms": round(elapsed_ns / 1e6, 2),
    }
    if args.out is not None:
        from tools.figures.pair_matches import write_pair_matches

        write_pair_matches(args.out, image_a, image_b, result)
        report["picture"] = str(args.out)
    print(json.dumps(report, indent=2))
    return 0
