"""Tests of robot/memory/verification.py: accepting a key image on a plausible relative pose."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robot.config import LocalizeConfig
from robot.memory.verification import (
    ACCEPTED,
    LOW_INLIER_RATIO,
    TOO_FEW_INLIERS,
    TOO_FEW_MATCHES,
    TOO_MUCH_TILT,
    TOO_MUCH_YAW,
    verify_bearings,
    yaw_tilt_deg,
)
from robot.vision._epipolar_error import rotation_y
from robot.vision.epipolar import rotation_from_rotvec
from shared.errors import DegenerateGeometryError, ShapeError

CONFIG = LocalizeConfig()
NOISE_RAD = 1.0 / 400.0


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def matched_bearings(
    rng: np.random.Generator, R_b_a: np.ndarray, t_b_a: np.ndarray, n: int = 120,
    outliers: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Level-frame bearings of ``n`` points 1-8 m around view b, seen from a and b (noisy),
    then ``outliers`` random pairs."""
    points_b = _unit(rng.normal(size=(n, 3))) * rng.uniform(1.0, 8.0, (n, 1))
    points_a = (points_b - 0.5 * t_b_a) @ R_b_a  # R^T (X_b - t), with a 0.5 m baseline
    fa = _unit(points_a + rng.normal(0.0, NOISE_RAD, (n, 3)) * np.linalg.norm(points_a, axis=1,
                                                                                keepdims=True))
    fb = _unit(points_b + rng.normal(0.0, NOISE_RAD, (n, 3)) * np.linalg.norm(points_b, axis=1,
                                                                                keepdims=True))
    return (np.vstack([fa, _unit(rng.normal(size=(outliers, 3)))]),
            np.vstack([fb, _unit(rng.normal(size=(outliers, 3)))]))


def planar_motion(yaw_deg: float, heading_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """A turn about the vertical (y, down) and a step in the floor's plane (x-z)."""
    h = math.radians(heading_deg)
    return rotation_y(math.radians(yaw_deg)), np.array([math.sin(h), 0.0, math.cos(h)])


class TestYawTilt:
    def test_a_turn_about_the_vertical(self) -> None:
        yaw, tilt = yaw_tilt_deg(rotation_y(math.radians(30.0)))
        assert yaw == pytest.approx(30.0) and tilt == pytest.approx(0.0, abs=1e-9)

    def test_a_roll_is_a_tilt(self) -> None:
        yaw, tilt = yaw_tilt_deg(rotation_from_rotvec(np.array([0.0, 0.0, math.radians(12.0)])))
        assert tilt == pytest.approx(12.0) and yaw == pytest.approx(0.0, abs=1e-9)

    def test_the_shape_is_checked(self) -> None:
        with pytest.raises(ShapeError):
            yaw_tilt_deg(np.eye(2))


class TestVerifyBearings:
    def test_a_true_pair_with_outliers_is_accepted(self, rng: np.random.Generator) -> None:
        R, t = planar_motion(20.0, 70.0)
        fa, fb = matched_bearings(rng, R, t, n=100, outliers=30)
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.verdict == ACCEPTED and result.accepted
        assert result.matches == 130
        assert 95 <= result.inliers <= 105
        assert result.inlier_ratio == pytest.approx(result.inliers / 130)
        assert result.yaw_deg == pytest.approx(20.0, abs=0.5)
        assert result.tilt_deg < 0.5

    def test_the_same_place_without_baseline_is_accepted(self, rng: np.random.Generator) -> None:
        # A photo taken where the key image was: the essential matrix is undetermined,
        # a rotation explains the matches.
        R, _ = planar_motion(10.0, 0.0)
        fa, fb = matched_bearings(rng, R, np.zeros(3), n=100, outliers=30)
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.verdict == ACCEPTED
        assert 95 <= result.inliers <= 105
        assert result.yaw_deg == pytest.approx(10.0, abs=0.5)
        assert math.isnan(result.along)  # no translation: no side

    @pytest.mark.parametrize("heading_deg", [30.0, 100.0, 160.0, -60.0])
    def test_along_is_the_side_the_query_lies_on(self, heading_deg: float,
                                                 rng: np.random.Generator) -> None:
        # The query's centre is at heading_deg from the key image's forward axis.
        R, t = planar_motion(5.0, heading_deg)
        fa, fb = matched_bearings(rng, R, t, n=100)
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.accepted
        assert result.along == pytest.approx(math.cos(math.radians(heading_deg)), abs=0.05)

    def test_random_matches_are_refused(self, rng: np.random.Generator) -> None:
        fa, fb = _unit(rng.normal(size=(200, 3))), _unit(rng.normal(size=(200, 3)))
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert not result.accepted
        assert result.verdict in (TOO_FEW_INLIERS, LOW_INLIER_RATIO)

    def test_a_turn_beyond_the_bound_is_refused(self, rng: np.random.Generator) -> None:
        R, t = planar_motion(CONFIG.max_yaw_deg + 15.0, 0.0)
        fa, fb = matched_bearings(rng, R, t)
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.verdict == TOO_MUCH_YAW
        assert result.yaw_deg == pytest.approx(CONFIG.max_yaw_deg + 15.0, abs=0.5)

    def test_a_rolled_camera_is_refused(self, rng: np.random.Generator) -> None:
        R = rotation_from_rotvec(np.array([0.0, 0.0, math.radians(CONFIG.max_tilt_deg + 10.0)]))
        fa, fb = matched_bearings(rng, R, np.array([0.0, 0.0, 1.0]))
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.verdict == TOO_MUCH_TILT
        assert result.tilt_deg == pytest.approx(CONFIG.max_tilt_deg + 10.0, abs=0.5)

    def test_too_few_inliers_even_if_all_agree(self, rng: np.random.Generator) -> None:
        R, t = planar_motion(5.0, 30.0)
        fa, fb = matched_bearings(rng, R, t, n=CONFIG.min_inliers - 1)
        result = verify_bearings(fa, fb, rng, CONFIG)
        assert result.verdict == TOO_FEW_MATCHES and result.inliers == 0
        assert math.isnan(result.yaw_deg) and math.isnan(result.tilt_deg)

    def test_a_low_ratio_is_refused(self, rng: np.random.Generator) -> None:
        R, t = planar_motion(5.0, 30.0)
        fa, fb = matched_bearings(rng, R, t, n=60, outliers=140)
        loose = verify_bearings(fa, fb, np.random.default_rng(1),
                                dataclasses.replace(CONFIG, min_inlier_ratio=0.2))
        strict = verify_bearings(fa, fb, np.random.default_rng(1), CONFIG)
        assert loose.accepted
        assert strict.verdict == LOW_INLIER_RATIO

    def test_shapes_and_bad_rows(self, rng: np.random.Generator) -> None:
        with pytest.raises(ShapeError, match="bearings_key"):
            verify_bearings(np.zeros((30, 3)), np.zeros((29, 3)), rng, CONFIG)
        bad = np.tile([0.0, 0.0, 1.0], (30, 1))
        bad[3] = (0.0, 0.0, 2.0)
        with pytest.raises(DegenerateGeometryError):
            verify_bearings(bad, np.tile([0.0, 0.0, 1.0], (30, 1)), rng, CONFIG)
