"""Real images (``vmnav bench real``): calibration and two-view geometry against references.

Three parts, each printed in one JSON document:

* ``catadioptric``: OpenCV's ``cv::omnidir`` test set (:mod:`tools.bench.realdata`; used
  in place, reported absent when it is) calibrated as ``vmnav calibrate`` does it
  (board detection, ``cv2.omnidir.calibrate``, the view checks); the focal lengths'
  relative errors and xi's error against OpenCV's reference.
* ``equidistant_fit``: the unified model fitted to each camera of the vendored fisheye
  pair (:func:`shared.kannala_brandt.fit_unified`): residual RMS and max, px, the fit's
  time.
* ``fisheye_pair``: the pair's relative pose by :func:`robot.vision.two_view.two_view`
  for each front end (the paper's Harris + ZNCC in its window, and the project's default
  over the whole image), against
  the reference from the two ``T_BS``
  (:func:`robot.vision.two_view.relative_pose_from_body`): rotation and translation
  direction errors, degrees, and the median time per pair on one core over
  ``--repeats`` runs (corners, descriptors, matching, lifting, RANSAC and refinement;
  the front ends, with their lens masks, are built once, not per pair).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from typing import Any

import numpy as np

from robot.config import FeatureConfig, LocalizeConfig, MatchConfig
from robot.vision.two_view import (
    TwoViewConfig,
    direction_error_deg,
    relative_pose_from_body,
    rotation_error_deg,
    rotation_vector_deg,
    two_cameras,
    two_view,
)
from shared.errors import InputError
from shared.image_decode import FILE_FORMATS, read_grey
from shared.kannala_brandt import fit_unified
from shared.kannala_brandt_yaml import read_equidistant_yaml
from tools.bench import realdata

#: The front ends compared on the fisheye pair, ``[features]`` and matching: the paper's
#: Harris + ZNCC in its search window (``[matching]``'s defaults), and the project's
#: default front end matched as localization matches (the whole image).
FRONT_ENDS: dict[str, tuple[FeatureConfig, MatchConfig]] = {
    "paper": (FeatureConfig(method="harris-zncc"), MatchConfig()),
    "default": (FeatureConfig(), LocalizeConfig().matching),
}
#: Targets of issue 16 (figure -> comparison, bound), read by :mod:`tools.bench.targets`.
TARGETS: dict[str, tuple[str, float]] = {
    "catadioptric.fx_error_rel": ("<=", realdata.FOCAL_TOLERANCE),
    "catadioptric.fy_error_rel": ("<=", realdata.FOCAL_TOLERANCE),
    "catadioptric.xi_error": ("<=", realdata.XI_TOLERANCE),
    "fisheye_pair.default.rotation_error_deg": ("<=", realdata.ROTATION_TOLERANCE_DEG),
    "fisheye_pair.default.direction_error_deg": ("<=", realdata.DIRECTION_TOLERANCE_DEG),
    "fisheye_pair.default.ms_per_pair_median": ("<", 30.0),
}


def bench_catadioptric() -> dict[str, Any]:
    """The catadioptric set calibrated, against OpenCV's reference (module docstring)."""
    from robot.calibration_checks import duplicate_views, outlier_views
    from robot.camera_calibration import calibrate_omnidir, find_board_corners
    from shared.errors import CalibrationError

    folder = realdata.CATADIOPTRIC_DIR
    if not folder.is_dir():
        return {"available": False, "reason": realdata.CATADIOPTRIC_MISSING}
    paths = sorted(folder.glob("*.jpg"), key=lambda p: int(p.stem) if p.stem.isdigit() else 0)
    images = [read_grey(p, error=CalibrationError, formats=FILE_FORMATS) for p in paths]
    board = realdata.CATADIOPTRIC_BOARD
    found = [(p, c) for p, image in zip(paths, images, strict=True)
             if (c := find_board_corners(image, board)) is not None]
    height, width = images[0].shape
    start_ns = time.perf_counter_ns()
    # fov_deg only bounds the valid rays of the RMS check: vmnav calibrate's default.
    result = calibrate_omnidir([c for _, c in found], board, (width, height), fov_deg=185.0,
                               where=folder)
    elapsed_s = (time.perf_counter_ns() - start_ns) / 1e9
    K, ref = result.camera.K, realdata.CATADIOPTRIC_REFERENCE
    return {
        "available": True,
        "views": len(paths),
        "boards_found": len(found),
        "views_used": len(result.used),
        "fx": float(K[0, 0]), "fy": float(K[1, 1]), "cx": float(K[0, 2]), "cy": float(K[1, 2]),
        "xi": result.camera.xi,
        "fx_error_rel": abs(K[0, 0] / ref["fx"] - 1.0),
        "fy_error_rel": abs(K[1, 1] / ref["fy"] - 1.0),
        "xi_error": abs(result.camera.xi - ref["xi"]),
        "rms_px": result.rms_px,
        "duplicate_views": len(duplicate_views([c for _, c in found], board)),
        "outlier_views": [found[result.used[k]][0].name
                          for k in outlier_views(result.view_rms_px)],
        "calibrate_s": elapsed_s,
        "reference": ref,
    }


def bench_fisheye_pair(repeats: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """The equidistant fits and the pair's relative pose per front end (module docstring)."""
    calibrations = [read_equidistant_yaml(path)
                    for path in (realdata.FISHEYE_LEFT_YAML, realdata.FISHEYE_RIGHT_YAML)]
    fits, fit_ms = [], []
    for calibration, name in zip(calibrations, ("left", "right"), strict=True):
        start_ns = time.perf_counter_ns()
        fits.append(fit_unified(calibration.camera, name))
        fit_ms.append((time.perf_counter_ns() - start_ns) / 1e6)
    fit_report = {
        name: {"rms_px": fit.rms_px, "max_px": fit.max_px, "xi": fit.camera.xi,
               "with_distortion": fit.with_distortion, "samples": fit.samples, "ms": ms}
        for name, fit, ms in zip(("left", "right"), fits, fit_ms, strict=True)
    }
    fit_report["max_px"] = max(fit.max_px for fit in fits)

    T_a, T_b = (c.T_body_sensor for c in calibrations)
    if T_a is None or T_b is None:
        raise InputError(realdata.FISHEYE_PAIR_DIR, "a camera's YAML has no T_BS: no reference")
    R_ref, t_ref = relative_pose_from_body(T_a, T_b)
    images = [read_grey(p, formats=FILE_FORMATS)
              for p in (realdata.FISHEYE_LEFT_IMAGE, realdata.FISHEYE_RIGHT_IMAGE)]
    pair: dict[str, Any] = {"reference": {
        "rotation_deg": float(np.linalg.norm(rotation_vector_deg(R_ref))),
        "baseline_m": float(np.linalg.norm(t_ref)),
        "translation_direction": (t_ref / np.linalg.norm(t_ref)).tolist(),
    }}
    for name, (features, matching) in FRONT_ENDS.items():
        cameras = two_cameras(fits[0].camera, fits[1].camera, features)
        config = TwoViewConfig(matching=matching)
        times_ms = []
        for k in range(repeats):
            start_ns = time.perf_counter_ns()
            result = two_view(images[0], images[1], cameras, config, np.random.default_rng(k))
            times_ms.append((time.perf_counter_ns() - start_ns) / 1e6)
        fit = result.fit
        pair[name] = {
            "method": features.method,
            "corners_a": len(result.corners_a),
            "corners_b": len(result.corners_b),
            "matches": len(result.matched_a),
            "inliers": fit.n_inliers,
            "ok": fit.ok,
            "rotation_error_deg": rotation_error_deg(fit.R_b_a, R_ref),
            "direction_error_deg": direction_error_deg(fit.t_b_a, t_ref),
            "ms_per_pair_median": statistics.median(times_ms),
            "ms_per_pair_min": min(times_ms),
        }
    return fit_report, pair


def run(args: argparse.Namespace) -> int:
    """Print the real-image benchmark's JSON (``vmnav bench real``)."""
    from tools.bench.cpu import pin_to_one_core

    if args.repeats < 1:
        raise InputError("--repeats", f"must be >= 1, got {args.repeats}")
    cpus = pin_to_one_core()
    fit_report, pair = bench_fisheye_pair(args.repeats)
    result = {
        "benchmark": "real",
        "cpus": cpus,
        "repeats": args.repeats,
        "catadioptric": bench_catadioptric(),
        "equidistant_fit": fit_report,
        "fisheye_pair": pair,
        "targets": {figure: f"{comparison} {bound:g}"
                    for figure, (comparison, bound) in TARGETS.items()},
    }
    print(json.dumps(result, indent=2))
    return 0
