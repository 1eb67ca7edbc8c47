"""Benchmark of features + matching on synthetic 800x600 pairs (one core).

Each run draws a textured image and a second view through a random small
homography (shift up to 10 px, rotation up to 1.5 deg, scale within 1.5 %, slight
tilt; every displacement stays inside the +-40 px window), a random global gain
and offset, and 2 grey levels of noise. A match is an inlier when B's corner lies
within 2 px of A's corner mapped through the true homography.

Pipelines:

* ``harris_zncc``: the paper's pipeline with the given configs (``method`` set to
  ``harris-zncc``);
* ``harris_zncc_integer``: the same without sub-pixel refinement;
* ``orb``, ``teblid``, ``beblid``: the front end's bit-string methods (FAST corners on a
  grid, upright descriptors), the same configs otherwise (``orb`` is the default);
* ``orb500_bf_crosscheck``: OpenCV ORB (500) + brute-force Hamming with cross
  check, the reference's fastest descriptor pipeline, for comparison only.

Timings depend on glibc's malloc: goodFeaturesToTrack allocates several 2-6 MB
buffers per call, and in a fresh process glibc returns them to the kernel and
page-faults them in again on every call, which about triples the detection time
(measured 9-10 ms against 3.5-4.7 ms per frame for detection + matching). Here
the synthesis of the pairs frees larger arrays first, which raises glibc's
dynamic thresholds, so these figures are the tuned case; a process gets it from
the start with ``MALLOC_TOP_PAD_=67108864`` (or ``mallopt``) in its environment.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, MatchConfig
from robot.vision.front_end import FrontEnd, make_front_end
from shared.camera_model import CameraModel
from sim.synthetic.image_pairs import (
    ImagePair,
    similarity_homography,
    transform_pixels,
    warped_pair,
)

#: A match is an inlier when it lies within this distance of the ground truth, px.
INLIER_TOLERANCE_PX = 2.0
#: Runs timed but not reported, to fill caches and let allocators settle.
_WARMUP_RUNS = 2

PixelPairs = tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]
#: A pipeline: (detect, match). detect(image) -> opaque features; match(fa, fb) -> matched pixels.
Pipeline = tuple[Callable[[npt.NDArray[np.uint8]], Any], Callable[[Any, Any], PixelPairs]]


def bench_features(
    runs: int = 20,
    seed: int = 0,
    features: FeatureConfig | None = None,
    matching: MatchConfig | None = None,
    width: int = 800,
    height: int = 600,
) -> dict[str, Any]:
    """Time detection and matching per pipeline and score the matches against ground truth.

    Sets OpenCV to one thread for the duration (restored afterwards); the caller
    should pin the process to one core so BLAS stays on it too.

    Args:
        runs: image pairs measured (after 2 warm-up pairs).
        seed: seed of the synthetic pairs.
        features: Harris/patch parameters; None = defaults.
        matching: ZNCC matching parameters; None = defaults.
        width: image width, px.
        height: image height, px.

    Returns:
        JSON-ready: ``runs``, ``image_size``, and per pipeline the medians over runs
        of ``detect_ms`` (one image), ``match_ms``, ``pair_ms`` (two detections and
        one matching), ``matches``, ``inlier_fraction`` and ``median_error_px``.
    """
    features = features or FeatureConfig()
    matching = matching or MatchConfig()
    camera = _camera(width, height)
    paper = dataclasses.replace(features, method="harris-zncc")
    pipelines = {
        "harris_zncc": _front_end(make_front_end(paper, camera), matching),
        "harris_zncc_integer": _front_end(make_front_end(
            dataclasses.replace(paper, subpixel_half_window_px=0), camera), matching),
        **{method: _front_end(make_front_end(dataclasses.replace(features, method=method),
                                             camera), matching)
           for method in ("orb", "teblid", "beblid")},
        "orb500_bf_crosscheck": _orb_bf(500),
    }
    rng = np.random.default_rng(seed)
    pairs = [_random_pair(rng, width, height) for _ in range(runs + _WARMUP_RUNS)]
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        results = {name: _measure(pipeline, pairs) for name, pipeline in pipelines.items()}
    finally:
        cv2.setNumThreads(threads)
    return {"runs": runs, "image_size": [width, height], **results}


def _random_pair(rng: np.random.Generator, width: int, height: int) -> ImagePair:
    H_b_a = similarity_homography(
        shift_xy=tuple(rng.uniform(-10.0, 10.0, 2)),
        rotation_rad=float(np.radians(rng.uniform(-1.5, 1.5))),
        scale=float(rng.uniform(0.985, 1.015)),
        centre_xy=(width / 2.0, height / 2.0),
        tilt=tuple(rng.uniform(-1e-5, 1e-5, 2)),
    )
    return warped_pair(rng, H_b_a, width, height, noise_sigma=2.0,
                       gain=float(rng.uniform(0.7, 1.3)), offset=float(rng.uniform(-20.0, 20.0)))


def _measure(pipeline: Pipeline, pairs: list[ImagePair]) -> dict[str, float]:
    detect, match = pipeline
    detect_ms, match_ms, pair_ms, counts, inliers, errors = [], [], [], [], [], []
    for k, pair in enumerate(pairs):
        t0 = time.perf_counter_ns()
        feats_a = detect(pair.image_a)
        t1 = time.perf_counter_ns()
        feats_b = detect(pair.image_b)
        t2 = time.perf_counter_ns()
        pixels_a, pixels_b = match(feats_a, feats_b)
        t3 = time.perf_counter_ns()
        if k < _WARMUP_RUNS:
            continue
        error_px = np.linalg.norm(transform_pixels(pair.H_b_a, pixels_a) - pixels_b, axis=1)
        detect_ms += [(t1 - t0) / 1e6, (t2 - t1) / 1e6]
        match_ms.append((t3 - t2) / 1e6)
        pair_ms.append((t3 - t0) / 1e6)
        counts.append(len(error_px))
        inliers.append(float(np.mean(error_px <= INLIER_TOLERANCE_PX)) if len(error_px) else 0.0)
        errors.append(float(np.median(error_px)) if len(error_px) else float("nan"))
    return {
        "detect_ms": round(float(np.median(detect_ms)), 3),
        "match_ms": round(float(np.median(match_ms)), 3),
        "pair_ms": round(float(np.median(pair_ms)), 3),
        "matches": float(np.median(counts)),
        "inlier_fraction": round(float(np.median(inliers)), 4),
        "median_error_px": round(float(np.median(errors)), 3),
    }


def _camera(width: int, height: int) -> CameraModel:
    """The default lens, its centre moved to the middle of a ``width`` x ``height`` image:
    the pairs are plane images, so only the image size matters (points anywhere)."""
    K = CameraModel.default().K.copy()
    K[0, 2], K[1, 2] = (width - 1) / 2.0, (height - 1) / 2.0
    return CameraModel(width=width, height=height, K=K, xi=CameraModel.default().xi, fov_deg=360.0)


def _front_end(front_end: FrontEnd, matching: MatchConfig) -> Pipeline:
    everywhere = np.ones((front_end.camera.height, front_end.camera.width), dtype=bool)

    def match(feats_a: Any, feats_b: Any) -> PixelPairs:
        return front_end.match(feats_a, feats_b, matching).pixels_xy(feats_a, feats_b)

    return (lambda image: front_end.describe(image, everywhere)), match


def _orb_bf(n_features: int) -> Pipeline:
    orb = cv2.ORB_create(n_features)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)

    def detect(image: npt.NDArray[np.uint8]) -> tuple[npt.NDArray[np.float64], Any]:
        keypoints, descriptors = orb.detectAndCompute(image, None)
        return np.array([kp.pt for kp in keypoints], dtype=np.float64).reshape(-1, 2), descriptors

    def match(feats_a: Any, feats_b: Any) -> PixelPairs:
        (pixels_a, desc_a), (pixels_b, desc_b) = feats_a, feats_b
        if desc_a is None or desc_b is None:
            return np.zeros((0, 2)), np.zeros((0, 2))
        pairs = matcher.match(desc_a, desc_b)
        idx_a = np.array([m.queryIdx for m in pairs], dtype=np.intp)
        idx_b = np.array([m.trainIdx for m in pairs], dtype=np.intp)
        return pixels_a[idx_a], pixels_b[idx_b]

    return detect, match
