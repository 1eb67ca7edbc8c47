"""Tests of robot/calibration_checks.py: duplicate and outlier views."""

from __future__ import annotations

import numpy as np

from robot.calibration_checks import DuplicateView, duplicate_views, outlier_views
from shared.chessboard import Chessboard

BOARD = Chessboard(cols=4, rows=3, square_m=0.03)


def grid(x0: float, y0: float, spacing: float = 20.0) -> np.ndarray:
    u, v = np.meshgrid(x0 + spacing * np.arange(4), y0 + spacing * np.arange(3))
    return np.stack([u.ravel(), v.ravel()], axis=1).astype(np.float64)


class TestDuplicateViews:
    def test_near_identical_poses(self) -> None:
        views = [grid(100, 100), grid(300, 100), grid(101, 102), grid(300, 100)[::-1]]
        found = duplicate_views(views, BOARD)
        assert [(d.earlier, d.later) for d in found] == [(0, 2), (1, 3)]
        assert found[0].rms_px == np.hypot(1, 2)
        assert found[1] == DuplicateView(1, 3, 0.0)  # the same board, corners reversed

    def test_a_quarter_square_apart_is_not_a_duplicate(self) -> None:
        assert duplicate_views([grid(100, 100), grid(106, 100)], BOARD) == []
        assert duplicate_views([grid(100, 100)], BOARD) == []


class TestOutlierViews:
    def test_one_view_far_worse(self) -> None:
        # OpenCV's catadioptric set: 12.jpg at 1.7 px against a median of 0.38 px.
        assert outlier_views([0.38, 0.40, 1.715, 0.31, 0.42]) == [2]

    def test_small_errors_are_never_outliers(self) -> None:
        assert outlier_views([0.05, 0.06, 0.5, 0.05]) == []
        assert outlier_views([0.1, 5.0]) == []  # too few views to tell
