"""A localization for people: the query read from a file, the result as JSON-ready data.

Shared by the commands that localize one image in a memory (``vmnav memory localize``,
``vmnav vision localize``): one reading of the query image, one form of the ranked
candidates with their scores (matches, verified inliers, inlier ratio, yaw, tilt) and
the verdict, so both print the same thing.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from robot.memory.localize import Candidate, Localization
from shared.errors import InputError
from shared.memory import VisualMemory


def read_query_image(path: Path, width: int, height: int) -> npt.NDArray[np.uint8]:
    """An 8-bit image file as a grey (height, width) array (colour is converted to grey).

    Raises:
        InputError: the file is missing, unreadable, not an 8-bit image or not
            ``width`` x ``height`` px.
    """
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
    return np.asarray(image, dtype=np.uint8)


def localization_json(memory: VisualMemory, result: Localization) -> dict[str, Any]:
    """The result: the winner, its scores, the verdict and the ranked candidates.

    Args:
        memory: the memory the result's key image ids belong to.
        result: a localization in it.

    Returns:
        ``keyframe_id``, ``ahead_id`` (where a route from the query starts), ``ok``,
        ``verdict``, ``matches``, ``inliers``, ``inlier_ratio``, ``query_features`` and
        ``candidates`` (best first, each :func:`candidate_json`).
    """
    best = result.candidates[0] if result.candidates else None
    return {
        "keyframe_id": result.keyframe_id,
        "ahead_id": result.ahead_id,
        "ok": result.ok,
        "verdict": result.verdict,
        "matches": result.matches,
        "inliers": result.inliers,
        "inlier_ratio": None if best is None else _ratio(best),
        "query_features": result.query_features,
        "candidates": [candidate_json(memory, c) for c in result.candidates],
    }


def candidate_json(memory: VisualMemory, candidate: Candidate) -> dict[str, Any]:
    """One candidate: where its key image is, its scores, and its verdict (None: not verified)."""
    keyframe = memory.keyframe(candidate.keyframe_id)
    v = candidate.verification
    return {
        "keyframe_id": candidate.keyframe_id,
        "path": memory.paths[keyframe.path_id].name,
        "index": keyframe.index,
        "distance_m": round(keyframe.distance_m, 3),
        "similarity": None if math.isnan(candidate.similarity) else round(candidate.similarity, 4),
        "matches": candidate.matches,
        "inliers": None if v is None else v.inliers,
        "inlier_ratio": _ratio(candidate),
        "path_support": None if math.isnan(candidate.support) else round(candidate.support, 1),
        "yaw_deg": None if v is None or math.isnan(v.yaw_deg) else round(v.yaw_deg, 2),
        "tilt_deg": None if v is None or math.isnan(v.tilt_deg) else round(v.tilt_deg, 2),
        "verdict": None if v is None else v.verdict,
        "along": None if v is None or math.isnan(v.along) else round(v.along, 3),
    }


def _ratio(candidate: Candidate) -> float | None:
    v = candidate.verification
    return None if v is None else round(v.inlier_ratio, 3)
