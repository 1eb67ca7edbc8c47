"""Checks of the views of a chessboard calibration: duplicates and outliers.

Neither stops a calibration; ``vmnav calibrate`` prints a warning for each, so that the
user can retake or drop a view.

* **Duplicate views** (near-identical board poses) add no information about the lens
  but weigh that pose twice. Two views are duplicates when their corners lie within
  :data:`DUPLICATE_SPACING_FRACTION` of a square of each other (RMS over the corners,
  against the smaller corner spacing of the two; the board's 180-degree symmetry, which
  reverses OpenCV's corner order, is allowed for). On OpenCV's 17 catadioptric views
  the closest two differ by 1.2 squares.
* **Outlier views** fit the model much worse than the others (a blurred board, a
  misdetected corner, a board that bent): a view RMS more than
  :data:`OUTLIER_MEDIAN_FACTOR` times the median view's and above
  :data:`OUTLIER_MIN_PX`. On that set one view (12.jpg) has 1.7 px against a median of
  0.38 px.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.chessboard import Chessboard, corner_spacing_px

FloatArray = npt.NDArray[np.float64]

#: Views whose corners are closer than this fraction of a square (RMS) are duplicates.
DUPLICATE_SPACING_FRACTION = 0.25
#: A view is an outlier when its RMS exceeds this many times the median view RMS ...
OUTLIER_MEDIAN_FACTOR = 3.0
#: ... and this many px.
OUTLIER_MIN_PX = 1.0


@dataclass(frozen=True, slots=True)
class DuplicateView:
    """View ``later`` repeats the board pose of view ``earlier`` (indices, earlier < later).

    Attributes:
        earlier: index of the first view.
        later: index of the view that repeats it.
        rms_px: RMS distance between their corners, px.
    """

    earlier: int
    later: int
    rms_px: float


def duplicate_views(corners_per_view: Sequence[FloatArray],
                    board: Chessboard) -> list[DuplicateView]:
    """Pairs of views with near-identical board poses (module docstring).

    Args:
        corners_per_view: per view, (cols * rows, 2) corner pixels in
            :meth:`Chessboard.object_points` order, px.
        board: the chessboard.

    Returns:
        One entry per view that repeats an earlier one (against the first it repeats),
        in view order.
    """
    duplicates = []
    for later in range(len(corners_per_view)):
        b = np.asarray(corners_per_view[later], dtype=np.float64)
        for earlier in range(later):
            a = np.asarray(corners_per_view[earlier], dtype=np.float64)
            rms = min(_rms(a, b), _rms(a, b[::-1]))
            spacing = min(corner_spacing_px(board, a), corner_spacing_px(board, b))
            if rms < DUPLICATE_SPACING_FRACTION * spacing:
                duplicates.append(DuplicateView(earlier, later, rms))
                break
    return duplicates


def outlier_views(view_rms_px: Sequence[float]) -> list[int]:
    """Indices of the views whose RMS error stands out (module docstring), ascending."""
    rms = np.asarray(view_rms_px, dtype=np.float64)
    if rms.size < 3:
        return []
    limit = max(OUTLIER_MEDIAN_FACTOR * float(np.median(rms)), OUTLIER_MIN_PX)
    return [int(i) for i in np.flatnonzero(rms > limit)]


def _rms(a: FloatArray, b: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))
