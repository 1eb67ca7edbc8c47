"""Choosing calibration views from a camera: a view is kept when its board covers parts of
the lens's image that no kept view covered (pure).

A fisheye model is pinned down by boards seen all over the image circle, the rim above
all, where the lens bends most and a board is hardest to hold; views that repeat the
centre add nothing. ``vmnav calibrate --capture`` feeds camera frames through
:class:`ViewPicker` and stops when the image is covered.

Rules:

1. The image is a grid of :data:`GRID` cells. A cell belongs to the lens's image when
   its mean grey over the frames seen so far exceeds :data:`DARK_LEVEL` (outside a
   fisheye's image circle the sensor stays black), so the coverage is of what the lens
   images, whatever its circle.
2. A board covers the cells inside the convex outline of its corners.
3. A frame with a board is kept when the board covers at least ``min_new_cells`` image
   cells that no kept view covers; other frames are skipped.
4. Coverage is the share of the image's cells that kept views cover. The capture is
   done when coverage reaches ``target`` with at least ``min_views`` views kept, or when
   ``max_views`` views are kept.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from robot.camera_calibration import find_board_corners
from shared.chessboard import Chessboard

#: Cells across and down the image (rule 1).
GRID = (16, 12)
#: A cell whose mean grey is at most this is outside the lens's image (rule 1), 0-255.
DARK_LEVEL = 12.0


@dataclass(frozen=True, slots=True)
class CaptureGoal:
    """When the capture is done (rules 3 and 4).

    Attributes:
        target: coverage to reach, the share of the lens's image, (0, 1].
        min_views: views to keep at least, >= 3 (``cv2.omnidir.calibrate`` needs them).
        max_views: views to keep at most, >= ``min_views``.
        min_new_cells: cells a view must add to be kept, >= 1.
    """

    target: float = 0.8
    min_views: int = 12
    max_views: int = 40
    min_new_cells: int = 3

    def __post_init__(self) -> None:
        if not 0.0 < self.target <= 1.0:
            raise ValueError(f"coverage target must be in (0, 1], got {self.target}")
        if self.min_views < 3:
            raise ValueError(f"at least 3 views are needed, got {self.min_views}")
        if self.max_views < self.min_views:
            raise ValueError(f"max views {self.max_views} < min views {self.min_views}")
        if self.min_new_cells < 1:
            raise ValueError(f"new cells per view must be >= 1, got {self.min_new_cells}")


@dataclass(frozen=True, slots=True)
class Look:
    """What one frame gave.

    Attributes:
        corners: (N, 2) board corners, px; None when no whole board was found.
        new_cells: image cells the board covers that no kept view covered.
        kept: the frame was kept as a calibration view.
        coverage: the share of the lens's image covered after this frame, [0, 1].
    """

    corners: npt.NDArray[np.float64] | None
    new_cells: int
    kept: bool
    coverage: float


class ViewPicker:
    """Rules 1-4 over a stream of grey frames of one size.

    Args:
        board: the chessboard held in front of the camera.
        goal: when to stop.
    """

    def __init__(self, board: Chessboard, goal: CaptureGoal) -> None:
        self.board = board
        self.goal = goal
        self.kept = 0
        """Views kept so far."""
        self._grey_sum = np.zeros(GRID[::-1], np.float64)
        self._frames = 0
        self._covered = np.zeros(GRID[::-1], bool)

    @property
    def coverage(self) -> float:
        """Rule 4's share, [0, 1] (0 before any frame)."""
        image = self._image_cells()
        return float((self._covered & image).sum() / max(1, image.sum()))

    @property
    def done(self) -> bool:
        """Rule 4."""
        return self.kept >= self.goal.max_views or (
            self.kept >= self.goal.min_views and self.coverage >= self.goal.target)

    def look(self, image: npt.NDArray[np.uint8]) -> Look:
        """Take one (H, W) uint8 grey frame (rules 1-3)."""
        height, width = image.shape
        cells = cv2.resize(image, GRID, interpolation=cv2.INTER_AREA).astype(np.float64)
        self._grey_sum += cells
        self._frames += 1
        corners = find_board_corners(image, self.board)
        if corners is None:
            return Look(None, 0, False, self.coverage)
        covered = np.zeros(GRID[::-1], np.uint8)
        scale = np.array([GRID[0] / width, GRID[1] / height])
        hull = cv2.convexHull((corners * scale).astype(np.float32))
        cv2.fillConvexPoly(covered, np.round(hull - 0.5).astype(np.int32).reshape(-1, 2), 1)
        new = int((covered.astype(bool) & ~self._covered & self._image_cells()).sum())
        kept = new >= self.goal.min_new_cells and not self.done
        if kept:
            self._covered |= covered.astype(bool)
            self.kept += 1
        return Look(corners, new, kept, self.coverage)

    def _image_cells(self) -> npt.NDArray[np.bool_]:
        return self._grey_sum / max(1, self._frames) > DARK_LEVEL
