"""Tests of robot/vision/two_view.py: the relative pose of two calibrated images."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from robot.config import FeatureConfig
from robot.vision.epipolar import rotation_from_rotvec
from robot.vision.two_view import (
    TwoViewConfig,
    direction_error_deg,
    relative_pose_from_body,
    rotation_error_deg,
    rotation_vector_deg,
    two_cameras,
    two_view,
)
from shared.camera_model import CameraModel
from shared.errors import ShapeError
from shared.kannala_brandt import fit_unified
from shared.kannala_brandt_yaml import read_equidistant_yaml
from tools.bench.realdata import (
    DIRECTION_TOLERANCE_DEG,
    FISHEYE_LEFT_IMAGE,
    FISHEYE_LEFT_YAML,
    FISHEYE_RIGHT_IMAGE,
    FISHEYE_RIGHT_YAML,
    ROTATION_TOLERANCE_DEG,
)

#: Harris + ZNCC with many corners (1000, down to 0.1 % of the strongest response): the
#: two-view pipeline with the paper's method, beside the default front end.
SPREAD = FeatureConfig(method="harris-zncc", max_corners=1000, quality_level=0.001)


def pose(rotvec: list[float], t: list[float]) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rotation_from_rotvec(np.array(rotvec))
    T[:3, 3] = t
    return T


class TestRelativePoseFromBody:
    def test_known_rig(self, rng: np.random.Generator) -> None:
        T_body_a = pose([0.1, -0.2, 0.3], [0.5, 0.0, -0.1])
        T_body_b = pose([-0.3, 0.1, 0.05], [0.2, 0.4, 0.3])
        R_b_a, t_b_a = relative_pose_from_body(T_body_a, T_body_b)
        # A point's coordinates in a and in b name the same body point.
        X_a = rng.normal(size=3)
        X_body = T_body_a[:3, :3] @ X_a + T_body_a[:3, 3]
        X_b = np.linalg.solve(T_body_b[:3, :3], X_body - T_body_b[:3, 3])
        assert np.allclose(R_b_a @ X_a + t_b_a, X_b)

    def test_the_fisheye_rig(self) -> None:
        left = read_equidistant_yaml(FISHEYE_LEFT_YAML).T_body_sensor
        right = read_equidistant_yaml(FISHEYE_RIGHT_YAML).T_body_sensor
        assert left is not None and right is not None
        R_b_a, t_b_a = relative_pose_from_body(left, right)
        # The README of the data: 0.120 m apart, along the left camera's x, 0.29 degrees.
        assert np.linalg.norm(t_b_a) == pytest.approx(0.120, abs=0.001)
        assert t_b_a[0] < -0.119  # the left camera sits at -x in the right one's frame
        assert rotation_error_deg(R_b_a, np.eye(3)) == pytest.approx(0.29, abs=0.01)

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError):
            relative_pose_from_body(np.eye(3), np.eye(4))


class TestAngles:
    def test_rotation_vector_round_trip(self, rng: np.random.Generator) -> None:
        for _ in range(20):
            w = rng.normal(size=3)
            w *= rng.uniform(0.0, 3.0) / np.linalg.norm(w)
            assert np.allclose(rotation_vector_deg(rotation_from_rotvec(w)), np.degrees(w))

    def test_errors(self) -> None:
        R = rotation_from_rotvec(np.radians([0.0, 0.0, 2.0]))
        assert rotation_error_deg(R, np.eye(3)) == pytest.approx(2.0)
        assert direction_error_deg([1.0, 0.0, 0.0], [5.0, 5.0, 0.0]) == pytest.approx(45.0)
        assert direction_error_deg([1.0, 0.0, 0.0], [-2.0, 0.0, 0.0]) == pytest.approx(180.0)


@pytest.fixture(scope="module")
def fisheye_cameras() -> tuple[CameraModel, CameraModel]:
    return (fit_unified(read_equidistant_yaml(FISHEYE_LEFT_YAML).camera, "left").camera,
            fit_unified(read_equidistant_yaml(FISHEYE_RIGHT_YAML).camera, "right").camera)


class TestTwoView:
    @pytest.mark.parametrize("features", [FeatureConfig(), SPREAD], ids=["default", "harris"])
    def test_the_real_fisheye_pair_within_the_issues_tolerances(
        self, fisheye_cameras: tuple[CameraModel, CameraModel], features: FeatureConfig
    ) -> None:
        image_a = cv2.imread(str(FISHEYE_LEFT_IMAGE), cv2.IMREAD_GRAYSCALE)
        image_b = cv2.imread(str(FISHEYE_RIGHT_IMAGE), cv2.IMREAD_GRAYSCALE)
        result = two_view(image_a, image_b, two_cameras(*fisheye_cameras, features),
                          TwoViewConfig(), np.random.default_rng(0))
        R_ref, t_ref = relative_pose_from_body(read_equidistant_yaml(FISHEYE_LEFT_YAML)
                                               .T_body_sensor,
                                               read_equidistant_yaml(FISHEYE_RIGHT_YAML)
                                               .T_body_sensor)
        fit = result.fit
        assert fit.ok and fit.model == "general"
        assert len(result.matched_a) == len(fit.inlier_mask) == len(result.matched_b)
        assert fit.n_inliers > 60
        assert rotation_error_deg(fit.R_b_a, R_ref) < ROTATION_TOLERANCE_DEG
        assert direction_error_deg(fit.t_b_a, t_ref) < DIRECTION_TOLERANCE_DEG
        assert math.isclose(float(np.linalg.norm(fit.t_b_a)), 1.0)

    def test_blank_images_give_no_pose(self) -> None:
        camera = CameraModel.default()
        blank = np.full((camera.height, camera.width), 90, np.uint8)
        result = two_view(blank, blank, two_cameras(camera, camera, FeatureConfig()),
                          TwoViewConfig(), np.random.default_rng(0))
        assert len(result.corners_a) == 0 and len(result.matched_a) == 0
        assert not result.fit.ok and result.fit.n_inliers == 0

    def test_image_of_the_wrong_size(self) -> None:
        camera = CameraModel.default()
        with pytest.raises(ShapeError):
            two_view(np.zeros((10, 10), np.uint8), np.zeros((600, 800), np.uint8),
                     two_cameras(camera, camera, FeatureConfig()), TwoViewConfig(),
                     np.random.default_rng(0))
