"""Tests of robot/vision/_epipolar_error.py: Sampson errors and their derivatives."""

from __future__ import annotations

import numpy as np

from robot.vision._epipolar_error import (
    EpipolarPairs,
    essentials,
    rotation_y,
    rotation_y_derivative,
)
from robot.vision.epipolar import epipolar_residuals_rad, rotation_from_rotvec


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


class TestEpipolarPairs:
    def test_batch_matches_one_at_a_time(self, rng: np.random.Generator) -> None:
        fa, fb = _unit(rng.normal(size=(30, 3))), _unit(rng.normal(size=(30, 3)))
        Rs = np.array([rotation_from_rotvec(w) for w in rng.normal(size=(70, 3))])
        ts = rng.normal(size=(70, 3))
        batch = EpipolarPairs(fa, fb).errors(essentials(Rs, ts))  # spans several chunks
        one = np.array([epipolar_residuals_rad(R, t, fa, fb) for R, t in zip(Rs, ts, strict=True)])
        assert batch.shape == (70, 30)
        np.testing.assert_allclose(batch, one, atol=1e-12)
        subset = EpipolarPairs(fa, fb).subset(np.arange(30) % 3 == 0)
        assert len(subset) == 10
        np.testing.assert_allclose(subset.errors(essentials(Rs, ts)), batch[:, ::3], atol=1e-12)

    def test_derivatives_match_finite_differences(self, rng: np.random.Generator) -> None:
        pairs = EpipolarPairs(_unit(rng.normal(size=(25, 3))), _unit(rng.normal(size=(25, 3))))

        def essential(x: np.ndarray) -> np.ndarray:
            return essentials(rotation_from_rotvec(x[:3])[None], x[3:][None])[0]

        x = rng.normal(size=6)
        h = 1e-7
        dEs = np.array([(essential(x + h * e) - essential(x)) / h for e in np.eye(6)])
        r, J = pairs.errors_and_derivatives(essential(x), dEs)
        numeric = np.column_stack([
            (pairs.errors(essential(x + h * e)[None])[0] - r) / h for e in np.eye(6)
        ])
        np.testing.assert_allclose(r, pairs.errors(essential(x)[None])[0], atol=1e-14)
        np.testing.assert_allclose(J, numeric, atol=1e-5)


def test_rotation_y_and_its_derivative() -> None:
    yaw, h = 0.3, 1e-7
    R = rotation_y(yaw)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(R @ [0.0, 0.0, 1.0], [np.sin(yaw), 0.0, np.cos(yaw)])
    np.testing.assert_allclose(rotation_y_derivative(yaw), (rotation_y(yaw + h) - R) / h,
                               atol=1e-6)
