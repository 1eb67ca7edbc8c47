"""Tests of robot/vision/epipolar.py: robust relative pose from unit bearings."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.config import RelativePoseConfig
from robot.vision._epipolar_error import rotation_y
from robot.vision.epipolar import epipolar_residuals_rad, relative_pose, rotation_from_rotvec
from shared.errors import DegenerateGeometryError, ShapeError

CONFIG = RelativePoseConfig()
#: 1 px on the default lens (about 174 px/rad), rad.
PIXEL_RAD = 1.0 / 174.0


@dataclass(frozen=True)
class BearingPair:
    """Matched unit rays of two views; ``X_b = R_b_a X_a + t_b_a``, |t_b_a| = 1."""

    R_b_a: np.ndarray
    t_b_a: np.ndarray
    bearings_a: np.ndarray
    bearings_b: np.ndarray
    outlier: np.ndarray


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _perturb(rng: np.random.Generator, f: np.ndarray, sigma_rad: float) -> np.ndarray:
    return _unit(f + rng.normal(0.0, sigma_rad, f.shape))


def bearing_pair(
    rng: np.random.Generator, n: int = 150, planar: bool = True, outlier_ratio: float = 0.2,
    noise_rad: float = PIXEL_RAD, max_off_axis_deg: float = 92.5,
) -> BearingPair:
    """Points 1-6 m around camera b seen within ``max_off_axis_deg`` of both optical axes.

    The planar motion is a yaw about y and a step in the x-z plane (a level camera on
    a flat floor); otherwise a general rotation and direction.
    """
    if planar:
        R = rotation_y(rng.uniform(-0.4, 0.4))
        heading = rng.uniform(-np.pi, np.pi)
        t = np.array([math.sin(heading), 0.0, math.cos(heading)])
    else:
        R = rotation_from_rotvec(rng.normal(0.0, 0.2, 3))
        t = _unit(rng.normal(size=(1, 3)))[0]
    baseline = rng.uniform(0.3, 1.0)
    points_b = np.empty((0, 3))
    cos_max = math.cos(math.radians(max_off_axis_deg))
    while len(points_b) < n:
        candidates = _unit(rng.normal(size=(4 * n, 3))) * rng.uniform(1.0, 6.0, (4 * n, 1))
        points_a = (candidates - baseline * t) @ R
        seen = (_unit(candidates)[:, 2] > cos_max) & (_unit(points_a)[:, 2] > cos_max)
        points_b = np.vstack([points_b, candidates[seen]])[:n]
    fb = _unit(points_b)
    fa = _unit((points_b - baseline * t) @ R)
    outlier = rng.random(n) < outlier_ratio
    fa[outlier] = _unit(rng.normal(size=(int(outlier.sum()), 3)))
    return BearingPair(R, t, _perturb(rng, fa, noise_rad), _perturb(rng, fb, noise_rad), outlier)


def _rotation_error_deg(R_est: np.ndarray, R_true: np.ndarray) -> float:
    return math.degrees(math.acos(np.clip((np.trace(R_est @ R_true.T) - 1.0) / 2.0, -1.0, 1.0)))


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))


class TestEpipolarResiduals:
    def test_smoke(self, rng: np.random.Generator) -> None:
        pair = bearing_pair(rng, outlier_ratio=0.0, noise_rad=0.0)
        r = epipolar_residuals_rad(pair.R_b_a, pair.t_b_a, pair.bearings_a, pair.bearings_b)
        assert r.shape == (150,)
        np.testing.assert_allclose(r, 0.0, atol=1e-12)

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError, match="bearings_b"):
            epipolar_residuals_rad(np.eye(3), np.ones(3), np.zeros((3, 3)), np.zeros((2, 3)))
        with pytest.raises(ShapeError, match="R_b_a"):
            epipolar_residuals_rad(np.eye(4), np.ones(3), np.zeros((3, 3)), np.zeros((3, 3)))

    def test_known_angle_out_of_the_epipolar_plane(self) -> None:
        # Sideways motion along x, R = I: a ray of b tilted by alpha out of the epipolar
        # plane of a's ray. In closed form g = -sin(alpha), |E f_a| = 1,
        # |E^T f_b| = 1, so r = -sin(alpha) / sqrt(2 - 2 sin^2 alpha) = -tan(alpha) / sqrt(2):
        # Sampson shares the error between the two rays.
        alpha = 0.01
        fa = np.array([[0.0, 0.0, 1.0]])
        fb = np.array([[0.0, math.sin(alpha), math.cos(alpha)]])
        r = epipolar_residuals_rad(np.eye(3), np.array([1.0, 0.0, 0.0]), fa, fb)
        assert r[0] == pytest.approx(-math.tan(alpha) / math.sqrt(2.0))

    @settings(max_examples=30, deadline=None)
    @given(st.integers(0, 2**31), st.floats(0.1, 10.0))
    def test_invariant_to_the_length_of_t_and_a_common_rotation(self, seed: int,
                                                               scale: float) -> None:
        rng = np.random.default_rng(seed)
        pair = bearing_pair(rng, n=20, planar=False, outlier_ratio=0.5)
        r = epipolar_residuals_rad(pair.R_b_a, pair.t_b_a, pair.bearings_a, pair.bearings_b)
        r_scaled = epipolar_residuals_rad(pair.R_b_a, scale * pair.t_b_a, pair.bearings_a,
                                          pair.bearings_b)
        Q = rotation_from_rotvec(rng.normal(size=3))  # rotate frame b
        r_rotated = epipolar_residuals_rad(Q @ pair.R_b_a, Q @ pair.t_b_a, pair.bearings_a,
                                           pair.bearings_b @ Q.T)
        np.testing.assert_allclose(r_scaled, r, atol=1e-10)
        np.testing.assert_allclose(r_rotated, r, atol=1e-10)


class TestRelativePose:
    def test_smoke(self, rng: np.random.Generator) -> None:
        pair = bearing_pair(rng, outlier_ratio=0.0, noise_rad=0.0)
        fit = relative_pose(pair.bearings_a, pair.bearings_b, rng, CONFIG)
        assert fit.ok and fit.model == "planar" and fit.n_inliers == 150
        np.testing.assert_allclose(fit.R_b_a, pair.R_b_a, atol=1e-6)
        np.testing.assert_allclose(fit.t_b_a, pair.t_b_a, atol=1e-6)
        assert fit.residual_rad.shape == (150,) and fit.parallax_rad > 0.0

    def test_shapes(self, rng: np.random.Generator) -> None:
        with pytest.raises(ShapeError, match="bearings_b"):
            relative_pose(np.eye(3), np.eye(3)[:2], rng, CONFIG)
        with pytest.raises(ShapeError, match="bearings_a"):
            relative_pose(np.zeros((4, 2)), np.zeros((4, 2)), rng, CONFIG)

    @pytest.mark.parametrize("planar", [True, False])
    def test_known_pose_with_noise_and_outliers(self, rng: np.random.Generator,
                                                planar: bool) -> None:
        """1 px noise, 20 % outliers, rays up to 92.5 degrees off axis; 20 scenes."""
        rotation_deg, direction_deg = [], []
        for _ in range(20):
            pair = bearing_pair(rng, planar=planar)
            assert np.count_nonzero(pair.bearings_a[:, 2] < 0) > 0
            fit = relative_pose(pair.bearings_a, pair.bearings_b, rng, CONFIG)
            assert fit.ok and fit.model == ("planar" if planar else "general")
            # Nearly every true inlier is kept and nearly no outlier is.
            assert np.mean(fit.inlier_mask[~pair.outlier]) > 0.9
            assert np.mean(fit.inlier_mask[pair.outlier]) < 0.1
            rotation_deg.append(_rotation_error_deg(fit.R_b_a, pair.R_b_a))
            direction_deg.append(_angle_deg(fit.t_b_a, pair.t_b_a))
        # The general model has 5 degrees of freedom against 2: looser bounds.
        rot_median, rot_max = (0.15, 0.6) if planar else (0.3, 0.8)
        assert np.median(rotation_deg) < rot_median and max(rotation_deg) < rot_max
        assert np.median(direction_deg) < 1.0 and max(direction_deg) < 4.0

    def test_rays_all_behind_the_image_planes(self, rng: np.random.Generator) -> None:
        """Only rays beyond 90 degrees in both views: pinhole x/z would fold every one."""
        R = rotation_y(0.02)
        t = np.array([0.8, 0.0, 0.0])  # view a is 0.8 m to the right of b
        theta = np.radians(rng.uniform(90.3, 92.0, 400))
        phi = rng.uniform(-np.pi, np.pi, 400)
        points_b = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                    np.cos(theta)]) * rng.uniform(1.5, 4.0, (400, 1))
        fb = _unit(points_b)
        fa = _unit((points_b - t) @ R)
        behind = (fa[:, 2] < 0) & (fa[:, 2] > math.cos(math.radians(92.5)))
        fa, fb = fa[behind][:80], fb[behind][:80]
        assert len(fa) == 80 and np.all(fb[:, 2] < 0)
        fit = relative_pose(_perturb(rng, fa, PIXEL_RAD), _perturb(rng, fb, PIXEL_RAD), rng,
                            CONFIG)
        assert fit.ok and fit.n_inliers >= 72
        assert _rotation_error_deg(fit.R_b_a, R) < 0.3
        assert _angle_deg(fit.t_b_a, t) < 3.0

    def test_auto_falls_back_to_five_points_for_a_tilted_camera(
        self, rng: np.random.Generator
    ) -> None:
        pair = bearing_pair(rng, planar=False)
        planar = relative_pose(pair.bearings_a, pair.bearings_b, rng,
                               dataclasses.replace(CONFIG, model="planar"))
        auto = relative_pose(pair.bearings_a, pair.bearings_b, rng, CONFIG)
        assert planar.n_inliers < 0.5 * len(pair.outlier)
        assert auto.model == "general" and auto.n_inliers > planar.n_inliers
        assert _rotation_error_deg(auto.R_b_a, pair.R_b_a) < 0.6

    def test_too_few_or_unrelated_matches_are_not_ok(self, rng: np.random.Generator) -> None:
        fit = relative_pose(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]), rng, CONFIG)
        assert not fit.ok and fit.model == "none" and fit.n_inliers == 0
        noise = relative_pose(_unit(rng.normal(size=(100, 3))), _unit(rng.normal(size=(100, 3))),
                              rng, dataclasses.replace(CONFIG, model="planar"))
        assert noise.n_inliers < 15

    def test_degenerate_bearings_raise(self, rng: np.random.Generator) -> None:
        good = _unit(rng.normal(size=(10, 3)))
        bad = good.copy()
        bad[3] = (0.0, 0.0, 2.0)
        with pytest.raises(DegenerateGeometryError, match="bearings_b: row 3"):
            relative_pose(good, bad, rng, CONFIG)
        bad[3] = (np.nan, 0.0, 1.0)
        with pytest.raises(DegenerateGeometryError, match="bearings_a: row 3"):
            relative_pose(bad, good, rng, CONFIG)

    def test_same_seed_same_fit(self) -> None:
        pair = bearing_pair(np.random.default_rng(3))
        fits = [relative_pose(pair.bearings_a, pair.bearings_b, np.random.default_rng(9), CONFIG)
                for _ in range(2)]
        np.testing.assert_array_equal(fits[0].R_b_a, fits[1].R_b_a)
        np.testing.assert_array_equal(fits[0].inlier_mask, fits[1].inlier_mask)
