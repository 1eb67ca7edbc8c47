"""``vmnav bench chance``: unrelated real images must never pass localization's acceptance test.

Issue 16: on real images two unrelated views share a median 30 chance ZNCC matches,
more than the old acceptance threshold of 25 matches. Localization now accepts a key
image on geometric verification (:mod:`robot.memory.verification`); this benchmark
tries it on every pair of *unrelated* real photographs and counts the pairs accepted
(target: none).

The images:

* the real camera sets of ``../shared/realdata`` (and their copies vendored under
  ``tests/fixtures/realdata``): each set is one place, so pairs within a set are
  related and skipped;
* scikit-image's photographs (``skimage/data``, the licences of
  ``skimage/data/_fetchers.py``: CC0 or public domain), when scikit-image is installed
  (a dev dependency): an astronaut, bricks, a camera man, a cat, a clock, coffee,
  coins, grass, gravel, a rocket launch, printed text; each is its own set.

Each image is made what the robot's camera delivers: grey, centre-cropped to the
camera's aspect and resized to its size (the default lens), and
goes through exactly what a query and a key image go through in
:class:`robot.memory.Localizer`: the front end's features in the lens circle
(``[features] method``), matching with
``[localize] matching``, lifting through the camera and the mount, the relative
pose and the tests (:func:`robot.memory.verify_matches`). Every unordered pair of
images from different sets is tried once.

Run: ``vmnav bench chance [--realdata DIR] [--config FILE]`` (JSON).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.memory import Verification, verify_matches
from robot.vision.front_end import make_front_end
from shared.camera_model import CameraModel
from shared.camera_mount import rotation_level_cam
from shared.errors import InputError
from shared.image_decode import read_grey

_REPO = Path(__file__).resolve().parents[2]
#: Real camera sets beside the repository (CI clones it beside a ``shared/`` folder).
DEFAULT_REALDATA = _REPO.parent / "shared" / "realdata"
#: The real sets vendored into the repository (a set found in both is read once).
VENDORED_REALDATA = _REPO / "tests" / "fixtures" / "realdata"
#: scikit-image's photographs used, ``skimage/data/<file>`` (CC0 or public domain).
SKIMAGE_FILES = (
    "astronaut.png", "brick.png", "camera.png", "chelsea.png", "clock_motion.png",
    "coffee.png", "coins.png", "grass.png", "gravel.png", "rocket.jpg", "text.png",
)
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
#: The paper's front end (Harris corners, ZNCC), tried beside the config's.
PAPER_METHOD = "harris-zncc"
#: The acceptance threshold before geometric verification, matches: the JSON counts the
#: pairs it would have accepted (``old_rule_accepted``), for comparison.
OLD_MIN_MATCHES = 25
#: Pairs listed in the JSON's ``closest`` (most inliers first).
_CLOSEST = 5


@dataclass(frozen=True, eq=False)
class ChanceImage:
    """One photograph, ready to be a query or a key image.

    Attributes:
        name: ``set/file``.
        group: its set: images of one set show one place and are never paired.
        image: (H, W) uint8 grey, the camera's size.
    """

    name: str
    group: str
    image: npt.NDArray[np.uint8]


@dataclass(frozen=True, slots=True)
class PairOutcome:
    """One unrelated pair through the acceptance test.

    Attributes:
        query: the first image's name.
        key: the second image's name.
        verification: its matches, inliers and verdict.
        time_ms: CPU time of the matching and the verification, ms.
    """

    query: str
    key: str
    verification: Verification
    time_ms: float


def fitted_to_camera(image: npt.NDArray[np.uint8], camera: CameraModel) -> npt.NDArray[np.uint8]:
    """``image`` centre-cropped to the camera's aspect and resized to its size (grey uint8)."""
    h, w = image.shape
    aspect = camera.width / camera.height
    if w / h > aspect:
        crop_w = round(h * aspect)
        image = image[:, (w - crop_w) // 2:(w - crop_w) // 2 + crop_w]
    else:
        crop_h = round(w / aspect)
        image = image[(h - crop_h) // 2:(h - crop_h) // 2 + crop_h]
    shrink = image.shape[1] > camera.width
    resized = cv2.resize(image, (camera.width, camera.height),
                         interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
    return np.asarray(resized, dtype=np.uint8)


def real_sets(roots: Sequence[Path]) -> dict[str, list[Path]]:
    """The image files of each set (a sub-folder) under ``roots``, a set's files read once.

    Raises:
        InputError: no root is a folder.
    """
    existing = [r for r in roots if r.is_dir()]
    if not existing:
        raise InputError(roots[0], "no such folder of real image sets")
    sets: dict[str, dict[str, Path]] = {}
    for root in existing:
        for folder in sorted(p for p in root.iterdir() if p.is_dir()):
            files = sets.setdefault(folder.name, {})
            for path in sorted(folder.iterdir()):
                if path.suffix.lower() in _IMAGE_SUFFIXES:
                    files.setdefault(path.name, path)
    return {name: list(files.values()) for name, files in sets.items() if files}


def skimage_paths() -> list[Path]:
    """scikit-image's photographs of :data:`SKIMAGE_FILES` (empty when it is not installed)."""
    spec = importlib.util.find_spec("skimage")
    if spec is None or spec.origin is None:
        return []
    folder = Path(spec.origin).parent / "data"
    return [folder / name for name in SKIMAGE_FILES if (folder / name).is_file()]


def load_images(roots: Sequence[Path], camera: CameraModel) -> list[ChanceImage]:
    """Every real set's images and scikit-image's photographs, fitted to ``camera``.

    Raises:
        InputError: a file does not decode, or no root is a folder.
    """
    images = [
        ChanceImage(f"{group}/{path.name}", group, fitted_to_camera(read_grey(path), camera))
        for group, paths in real_sets(roots).items() for path in paths
    ]
    images += [
        ChanceImage(f"skimage/{path.name}", f"skimage/{path.stem}",
                    fitted_to_camera(read_grey(path), camera))
        for path in skimage_paths()
    ]
    return images


def try_pairs(
    images: Sequence[ChanceImage], camera: CameraModel, config: VmnavConfig, seed: int = 0
) -> list[PairOutcome]:
    """Every unordered pair of images from different sets through localization's test."""
    front_end = make_front_end(config.features, camera)
    features = [front_end.describe(i.image) for i in images]
    R_level_cam = rotation_level_cam(config.camera.mount)
    outcomes = []
    for a in range(len(images)):
        for b in range(a + 1, len(images)):
            if images[a].group == images[b].group:
                continue
            t0 = time.thread_time_ns()
            matches = front_end.match(features[a], features[b], config.localize.matching)
            verification = verify_matches(features[a], features[b], matches, R_level_cam,
                                          config.localize, np.random.default_rng(seed))
            time_ms = (time.thread_time_ns() - t0) / 1e6
            outcomes.append(PairOutcome(images[a].name, images[b].name, verification, time_ms))
    return outcomes


def summary(images: Sequence[ChanceImage], outcomes: Sequence[PairOutcome]) -> dict[str, Any]:
    """JSON-ready counts: pairs tried and accepted, the largest inlier count, the closest pairs."""
    v = [o.verification for o in outcomes]
    matches = np.array([x.matches for x in v]) if v else np.zeros(1)
    return {
        "images": len(images),
        "sets": dict(Counter(i.group.split("/")[0] for i in images)),
        "pairs": len(outcomes),
        "accepted": sum(x.accepted for x in v),
        "old_rule_accepted": sum(x.matches >= OLD_MIN_MATCHES for x in v),
        "max_inliers": max((x.inliers for x in v), default=0),
        "max_inlier_ratio": round(max((x.inlier_ratio for x in v), default=0.0), 3),
        "matches_median": float(np.median(matches)),
        "matches_p95": float(np.percentile(matches, 95)),
        "matches_max": int(matches.max()),
        "verdicts": dict(Counter(x.verdict for x in v)),
        "ms_per_pair_median": round(float(np.median([o.time_ms for o in outcomes])), 2)
        if outcomes else None,
        "closest": [_pair_json(o) for o in sorted(
            outcomes, key=lambda o: (o.verification.inliers, o.verification.matches),
            reverse=True)[:_CLOSEST]],
        "accepted_pairs": [_pair_json(o) for o in outcomes if o.verification.accepted],
    }


def _pair_json(outcome: PairOutcome) -> dict[str, Any]:
    v = outcome.verification
    return {"query": outcome.query, "key": outcome.key, "matches": v.matches,
            "inliers": v.inliers, "inlier_ratio": round(v.inlier_ratio, 3),
            "yaw_deg": None if np.isnan(v.yaw_deg) else round(v.yaw_deg, 1),
            "tilt_deg": None if np.isnan(v.tilt_deg) else round(v.tilt_deg, 1),
            "verdict": v.verdict}


def run(args: argparse.Namespace) -> int:
    """Print the benchmark's JSON (one core): the config's front end, and the paper's
    (``harris-zncc``) beside it under ``paper_front_end`` (the same figures when the
    config's is the paper's)."""
    import dataclasses

    from robot.config import load_config
    from tools.bench.cpu import pin_to_one_core
    from tools.bench.targets import target_summary

    config = load_config(args.config)
    camera = CameraModel.default()
    cpus = pin_to_one_core()
    realdata = DEFAULT_REALDATA if args.realdata is None else args.realdata
    images = load_images([realdata, VENDORED_REALDATA], camera)
    row = summary(images, try_pairs(images, camera, config))
    paper = dataclasses.replace(
        config, features=dataclasses.replace(config.features, method=PAPER_METHOD))
    paper_row = row if paper == config else summary(images, try_pairs(images, camera, paper))
    result: dict[str, Any] = {"benchmark": "chance", "cpus": cpus,
                              "camera_px": [camera.width, camera.height],
                              "front_end": config.features.method, **row,
                              "paper_front_end": {"front_end": PAPER_METHOD, **paper_row}}
    result.update(target_summary("chance", result))
    print(json.dumps(result, indent=2))
    return 0
