"""Tests of sim/checkerboard.py: synthetic chessboard views through the fisheye."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.camera_calibration import find_board_corners
from shared.camera_model import CameraModel
from shared.chessboard import Chessboard
from shared.errors import ShapeError
from sim.checkerboard import (
    BACKGROUND,
    DARK,
    DEFAULT_BOARD,
    LIGHT,
    UNSEEN,
    BoardPose,
    render_board,
    sample_board_poses,
    write_synthetic_set,
)

DISTORTED = CameraModel(
    800, 600, CameraModel.default().K, 1.6, np.array([-0.05, 0.01, 0.001, -0.0005])
)
BOARD = DEFAULT_BOARD


def face_on_pose(
    camera: CameraModel,
    pixel_xy: tuple[float, float],
    board_xy_m: tuple[float, float],
    distance_m: float,
) -> BoardPose:
    """Board parallel to the image plane at z = distance, with board point
    ``board_xy_m`` on the ray through ``pixel_xy``."""
    bearing, valid = camera.lift(np.array([pixel_xy]))
    assert valid[0]
    hit = bearing[0] * distance_m / bearing[0, 2]
    return BoardPose(R_c_b=np.eye(3), t_c_b=hit - np.array([*board_xy_m, 0.0]))


def off_axis_deg(points_c: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(points_c[:, 2] / np.linalg.norm(points_c, axis=1)))


class TestBoardPose:
    def test_shape_errors(self) -> None:
        with pytest.raises(ShapeError, match="R_c_b"):
            BoardPose(R_c_b=np.eye(2), t_c_b=np.zeros(3))
        with pytest.raises(ShapeError, match="t_c_b"):
            BoardPose(R_c_b=np.eye(3), t_c_b=np.zeros((3, 1)))


class TestRenderBoard:
    def test_smoke(self) -> None:
        pose = face_on_pose(CameraModel.default(), (399.5, 299.5), (0.1, 0.06), 0.4)
        view = render_board(CameraModel.default(), BOARD, pose)
        assert view.image.shape == (600, 800) and view.image.dtype == np.uint8
        assert view.corners_xy.shape == (54, 2) and view.corners_valid.all()

    def test_known_tones(self) -> None:
        cam = CameraModel.default()
        s = BOARD.square_m
        # Pixel (300, 300) sees the middle of square (0, 0), which is dark ...
        view = render_board(cam, BOARD, face_on_pose(cam, (300.0, 300.0), (0.5 * s, 0.5 * s), 0.3))
        assert view.image[300, 300] == DARK
        # ... and the middle of square (1, 0), which is light.
        view = render_board(cam, BOARD, face_on_pose(cam, (300.0, 300.0), (1.5 * s, 0.5 * s), 0.3))
        assert view.image[300, 300] == LIGHT
        # The paper margin is light, the world beyond it mid-grey, and
        # the image corners, outside the 185 degree image circle, black.
        view = render_board(cam, BOARD, face_on_pose(cam, (300.0, 300.0), (-1.5 * s, 0.5 * s), 0.3))
        assert view.image[300, 300] == LIGHT
        view = render_board(cam, BOARD, face_on_pose(cam, (300.0, 300.0), (-2.5 * s, 0.5 * s), 0.3))
        assert view.image[300, 300] == BACKGROUND
        assert view.image[0, 0] == view.image[599, 799] == UNSEEN

    def test_edge_pixel_is_anti_aliased(self) -> None:
        # The edge x_b = 0 between squares (-1, 0) (light) and (0, 0) (dark) runs
        # through the centre of pixel (400, 310): half of it is each tone.
        cam = CameraModel.default()
        pose = face_on_pose(cam, (400.0, 310.0), (0.0, 0.5 * BOARD.square_m), 0.4)
        image = render_board(cam, BOARD, pose).image
        assert abs(int(image[310, 400]) - (DARK + LIGHT) / 2) <= 2
        assert image[310, 395] == LIGHT and image[310, 405] == DARK

    def test_true_corner_pixels(self) -> None:
        cam = DISTORTED
        # Inner corner 0 is the board origin; put it on the ray of pixel (520.25, 180.75).
        pose = face_on_pose(cam, (520.25, 180.75), (0.0, 0.0), 0.5)
        view = render_board(cam, BOARD, pose)
        np.testing.assert_allclose(view.corners_xy[0], [520.25, 180.75], atol=1e-9)
        expected, _ = cam.project(BOARD.object_points() + pose.t_c_b)
        np.testing.assert_allclose(view.corners_xy, expected, atol=1e-12)

    def test_corners_out_of_view_are_flagged(self) -> None:
        # The board hangs off the right edge of a narrow image.
        cam = CameraModel(
            300, 600, CameraModel.default().K - [[0, 0, 250], [0, 0, 0], [0, 0, 0]], 1.6
        )
        view = render_board(cam, BOARD, face_on_pose(cam, (280.0, 300.0), (0.0, 0.06), 0.4))
        assert view.corners_valid.any() and not view.corners_valid.all()

    @pytest.mark.parametrize(
        "camera", [CameraModel.default(), DISTORTED], ids=["default", "distorted"]
    )
    def test_corners_are_found_to_sub_pixel_accuracy(
        self, camera: CameraModel, rng: np.random.Generator
    ) -> None:
        errors = []
        for pose in sample_board_poses(camera, BOARD, rng, 3):
            view = render_board(camera, BOARD, pose)
            found = find_board_corners(view.image, BOARD)
            assert found is not None
            # OpenCV may number the grid from the opposite corner (a 180 degree turn).
            err = min(
                np.linalg.norm(found - view.corners_xy, axis=1),
                np.linalg.norm(found[::-1] - view.corners_xy, axis=1),
                key=lambda e: float(e.max()),
            )
            errors.append(err)
        err = np.concatenate(errors)
        assert np.sqrt(np.mean(err**2)) < 0.15
        assert err.max() < 0.3

    def test_rays_behind_the_image_plane(self) -> None:
        # A big board beside the camera, in the plane x_c = 3 m, seen 88 to 92
        # degrees off the optical axis: beyond the image plane, inside the lens.
        cam = CameraModel.default()
        board = Chessboard(3, 3, 0.1)
        R_c_b = np.array(
            [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        )  # x_b -> y_c, y_b -> z_c
        pose = BoardPose(R_c_b=R_c_b, t_c_b=np.array([3.0, -0.1, -0.1]))
        view = render_board(cam, board, pose)
        angles = off_axis_deg(board.object_points() @ R_c_b.T + pose.t_c_b)
        assert angles.min() < 89.0 and 91.0 < angles.max() < 92.5
        assert view.corners_valid.all()
        # The middle of dark square (0, 0), 91 degrees off axis, is where the model says.
        centre_c = R_c_b @ np.array([0.05, 0.05, 0.0]) + pose.t_c_b
        pixels, valid = cam.project(centre_c[None, :])
        assert valid[0] and off_axis_deg(centre_c[None, :])[0] > 90.5
        u, v = np.rint(pixels[0]).astype(int)
        assert view.image[v, u] == DARK

    def test_supersample_must_be_positive(self) -> None:
        pose = face_on_pose(CameraModel.default(), (399.5, 299.5), (0.1, 0.06), 0.4)
        with pytest.raises(ValueError, match="supersample"):
            render_board(CameraModel.default(), BOARD, pose, supersample=0)


class TestSampleBoardPoses:
    def test_every_corner_visible_and_centre_and_rim_covered(
        self, rng: np.random.Generator
    ) -> None:
        poses = sample_board_poses(DISTORTED, BOARD, rng, 12)
        assert len(poses) == 12
        centres, corner_angles = [], []
        for pose in poses:
            np.testing.assert_allclose(pose.R_c_b @ pose.R_c_b.T, np.eye(3), atol=1e-12)
            assert np.linalg.det(pose.R_c_b) == pytest.approx(1.0)
            corners_c = BOARD.object_points() @ pose.R_c_b.T + pose.t_c_b
            _, valid = DISTORTED.project(corners_c)
            assert valid.all()
            centres.append(off_axis_deg(corners_c.mean(axis=0, keepdims=True))[0])
            corner_angles.append(off_axis_deg(corners_c))
        assert min(centres) < 10.0
        assert np.concatenate(corner_angles).max() > 80.0

    def test_seeded(self) -> None:
        a = sample_board_poses(DISTORTED, BOARD, np.random.default_rng(5), 4)
        b = sample_board_poses(DISTORTED, BOARD, np.random.default_rng(5), 4)
        for p, q in zip(a, b, strict=True):
            np.testing.assert_array_equal(p.R_c_b, q.R_c_b)
            np.testing.assert_array_equal(p.t_c_b, q.t_c_b)

    def test_impossible_camera(self, rng: np.random.Generator) -> None:
        tiny = CameraModel(
            20, 20, np.array([[10.0, 0, 9.5], [0, 10.0, 9.5], [0, 0, 1]]), 0.0, fov_deg=10.0
        )
        with pytest.raises(ValueError, match="no board pose for view 0"):
            sample_board_poses(tiny, BOARD, rng, 1, max_tries=20)


def test_write_synthetic_set(tmp_path: Path, rng: np.random.Generator) -> None:
    paths = write_synthetic_set(
        tmp_path / "views", CameraModel.default(), rng, 2, Chessboard(7, 5, 0.03)
    )
    assert [p.name for p in paths] == ["view_000.png", "view_001.png"]
    for path in paths:
        image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        assert image.shape == (600, 800) and image.dtype == np.uint8
        assert find_board_corners(image, Chessboard(7, 5, 0.03)) is not None
