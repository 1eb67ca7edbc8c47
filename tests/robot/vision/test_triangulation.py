"""Tests of robot/vision/triangulation.py: two-view triangulation of unit bearings."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from robot.vision.epipolar import rotation_from_rotvec
from robot.vision.triangulation import cross_rows, ray_depths, skew, triangulate_bearings
from shared.errors import ShapeError


@dataclass(frozen=True)
class TwoViews:
    """Points seen from two cameras; ``X_b = R_b_a X_a + t_b_a``."""

    R_b_a: np.ndarray
    t_b_a: np.ndarray
    points_b: np.ndarray
    bearings_a: np.ndarray
    bearings_b: np.ndarray


def two_views(rng: np.random.Generator, n: int = 100) -> TwoViews:
    """Points all around both cameras (half of them behind each image plane)."""
    R = rotation_from_rotvec(rng.normal(0.0, 0.3, 3))
    t = rng.normal(0.0, 1.0, 3)
    points_b = rng.normal(0.0, 4.0, (n, 3))
    points_a = (points_b - t) @ R  # R^T (X_b - t)
    return TwoViews(
        R_b_a=R, t_b_a=t, points_b=points_b,
        bearings_a=points_a / np.linalg.norm(points_a, axis=1, keepdims=True),
        bearings_b=points_b / np.linalg.norm(points_b, axis=1, keepdims=True),
    )


class TestHelpers:
    def test_skew_and_cross_rows_are_cross_products(self, rng: np.random.Generator) -> None:
        a, b = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
        np.testing.assert_allclose(cross_rows(a, b), np.cross(a, b), atol=1e-12)
        np.testing.assert_allclose(skew(a[0]) @ b[0], np.cross(a[0], b[0]), atol=1e-12)


class TestRayDepths:
    def test_smoke(self) -> None:
        # Camera a one metre to the right of b (x), a point 2 m ahead of b.
        d = ray_depths(np.eye(3), np.array([1.0, 0.0, 0.0]),
                       np.array([[-1.0, 0.0, 2.0]]) / np.sqrt(5.0), np.array([[0.0, 0.0, 1.0]]))
        np.testing.assert_allclose(d.depth_b, [2.0])
        np.testing.assert_allclose(d.depth_a, [np.sqrt(5.0)])
        np.testing.assert_allclose(d.parallax_rad, [np.arctan(0.5)])

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError, match="bearings_b"):
            ray_depths(np.eye(3), np.zeros(3), np.zeros((4, 3)), np.zeros((5, 3)))
        with pytest.raises(ShapeError, match="t_b_a"):
            ray_depths(np.eye(3), np.zeros(2), np.zeros((4, 3)), np.zeros((4, 3)))

    def test_known_depths_and_sign_for_points_behind_the_image_plane(
        self, rng: np.random.Generator
    ) -> None:
        v = two_views(rng)
        d = ray_depths(v.R_b_a, v.t_b_a, v.bearings_a, v.bearings_b)
        np.testing.assert_allclose(d.depth_b, np.linalg.norm(v.points_b, axis=1), rtol=1e-8)
        np.testing.assert_allclose(d.depth_a, np.linalg.norm(v.points_b - v.t_b_a, axis=1),
                                   rtol=1e-8)
        assert np.count_nonzero(v.bearings_b[:, 2] < 0) > 20  # rays beyond 90 degrees
        # The reversed baseline puts every point behind both cameras.
        flipped = ray_depths(v.R_b_a, -v.t_b_a, v.bearings_a, v.bearings_b)
        assert np.all(flipped.depth_a < 0) and np.all(flipped.depth_b < 0)

    def test_parallel_rays_have_no_depth(self) -> None:
        f = np.array([[0.0, 0.0, 1.0]])
        d = ray_depths(np.eye(3), np.array([1.0, 0.0, 0.0]), f, f)
        assert np.isnan(d.depth_a[0]) and np.isnan(d.depth_b[0])
        assert d.parallax_rad[0] == 0.0


class TestTriangulateBearings:
    def test_smoke(self) -> None:
        tri = triangulate_bearings(np.eye(3), np.array([1.0, 0.0, 0.0]),
                                   np.array([[-1.0, 0.0, 2.0]]) / np.sqrt(5.0),
                                   np.array([[0.0, 0.0, 1.0]]))
        np.testing.assert_allclose(tri.points_b, [[0.0, 0.0, 2.0]], atol=1e-12)
        assert tri.in_front.tolist() == [True]

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError, match="R_b_a"):
            triangulate_bearings(np.eye(2), np.zeros(3), np.zeros((4, 3)), np.zeros((4, 3)))

    def test_known_points_with_noise(self, rng: np.random.Generator) -> None:
        v = two_views(rng, 300)
        exact = triangulate_bearings(v.R_b_a, v.t_b_a, v.bearings_a, v.bearings_b)
        np.testing.assert_allclose(exact.points_b, v.points_b, atol=1e-8)
        assert exact.in_front.all()
        # 1 mrad of noise: the error grows with distance over parallax, as expected.
        noisy_a = v.bearings_a + rng.normal(0.0, 1e-3, v.bearings_a.shape)
        noisy_b = v.bearings_b + rng.normal(0.0, 1e-3, v.bearings_b.shape)
        noisy_a /= np.linalg.norm(noisy_a, axis=1, keepdims=True)
        noisy_b /= np.linalg.norm(noisy_b, axis=1, keepdims=True)
        tri = triangulate_bearings(v.R_b_a, v.t_b_a, noisy_a, noisy_b)
        good = tri.depths.parallax_rad > np.radians(10.0)
        distance = np.linalg.norm(v.points_b, axis=1)
        error = np.linalg.norm(tri.points_b - v.points_b, axis=1)
        assert np.median(error[good] / distance[good]) < 0.01

    def test_degenerate_parallel_rays_are_not_in_front(self) -> None:
        f = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
        tri = triangulate_bearings(np.eye(3), np.array([1.0, 0.0, 0.0]), f, f)
        assert not tri.in_front.any()
        assert np.isnan(tri.points_b).all()
