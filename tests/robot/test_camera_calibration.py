"""Tests of robot/camera_calibration.py: corner finding and the omnidir fit."""

from __future__ import annotations

import numpy as np
import pytest

from robot.camera_calibration import MIN_VIEWS, calibrate_omnidir, find_board_corners
from shared.camera_model import CameraModel
from shared.chessboard import Chessboard
from shared.errors import CalibrationError, ShapeError
from sim.checkerboard import render_board, sample_board_poses

BOARD = Chessboard(9, 6, 0.025)
TRUTH = CameraModel(800, 600, CameraModel.default().K, 1.3, np.array([-0.1, 0.02, 5e-4, -5e-4]))


def exact_corners(rng: np.random.Generator, n_views: int) -> list[np.ndarray]:
    """True corner pixels of ``n_views`` board poses, no image involved."""
    points = BOARD.object_points()
    return [
        TRUTH.project(points @ pose.R_c_b.T + pose.t_c_b)[0]
        for pose in sample_board_poses(TRUTH, BOARD, rng, n_views)
    ]


class TestFindBoardCorners:
    def test_finds_a_rendered_board(self, rng: np.random.Generator) -> None:
        view = render_board(TRUTH, BOARD, sample_board_poses(TRUTH, BOARD, rng, 1)[0])
        corners = find_board_corners(view.image, BOARD)
        assert corners is not None and corners.shape == (54, 2) and corners.dtype == np.float64
        # Same corners as the truth, possibly numbered from the opposite end.
        err = min(
            np.abs(corners - view.corners_xy).max(), np.abs(corners[::-1] - view.corners_xy).max()
        )
        assert err < 0.3

    def test_no_board(self) -> None:
        assert find_board_corners(np.full((600, 800), 128, np.uint8), BOARD) is None

    def test_wrong_pattern_size(self, rng: np.random.Generator) -> None:
        view = render_board(TRUTH, BOARD, sample_board_poses(TRUTH, BOARD, rng, 1)[0])
        assert find_board_corners(view.image, Chessboard(10, 7, 0.025)) is None

    def test_colour_image_is_a_shape_error(self) -> None:
        with pytest.raises(ShapeError, match="image"):
            find_board_corners(np.zeros((600, 800, 3), np.uint8), BOARD)


class TestCalibrateOmnidir:
    def test_exact_corners_give_the_truth(self, rng: np.random.Generator) -> None:
        result = calibrate_omnidir(
            exact_corners(rng, 8), BOARD, (800, 600), fov_deg=185.0, where="views"
        )
        assert result.used == tuple(range(8))
        assert len(result.view_rms_px) == 8
        assert result.rms_px < 1e-6
        assert max(result.view_rms_px) < 1e-6
        assert result.camera.fov_deg == 185.0
        assert (result.camera.width, result.camera.height) == (800, 600)
        # Compare by reprojection: xi and f trade off against the distortion.
        u, v = np.meshgrid(np.arange(0.0, 800.0, 8.0), np.arange(0.0, 600.0, 8.0))
        bearings, valid = TRUTH.lift(np.stack([u.ravel(), v.ravel()], axis=1))
        pixels, _ = TRUTH.project(bearings[valid])
        recovered, ok = result.camera.project(bearings[valid])
        assert ok.all()
        assert np.abs(recovered - pixels).max() < 1e-4

    def test_too_few_views(self, rng: np.random.Generator) -> None:
        with pytest.raises(CalibrationError, match=f"found in 2 image.*need at least {MIN_VIEWS}"):
            calibrate_omnidir(
                exact_corners(rng, 2), BOARD, (800, 600), fov_deg=185.0, where="views"
            )

    def test_garbage_corners_are_rejected(self, rng: np.random.Generator) -> None:
        garbage = [rng.uniform(0.0, 600.0, (54, 2)) for _ in range(4)]
        with pytest.raises(
            CalibrationError, match=r"^my_views: (cv2\.omnidir\.calibrate|calibration)"
        ):
            calibrate_omnidir(garbage, BOARD, (800, 600), fov_deg=185.0, where="my_views")

    def test_fronto_parallel_copies_diverge(self) -> None:
        # The same undistorted, face-on view three times: nothing fixes the focal length.
        flat = BOARD.object_points()[:, :2] * 1000.0 + 100.0
        with pytest.raises(CalibrationError, match="my_views: calibration diverged"):
            calibrate_omnidir([flat] * 3, BOARD, (800, 600), fov_deg=185.0, where="my_views")

    def test_corner_shape_error(self, rng: np.random.Generator) -> None:
        views = exact_corners(rng, 3)
        views[1] = views[1][:50]
        with pytest.raises(ShapeError, match=r"corners_per_view\[1\]"):
            calibrate_omnidir(views, BOARD, (800, 600), fov_deg=185.0, where="views")
