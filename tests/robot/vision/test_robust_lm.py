"""Tests of robot/vision/_robust_lm.py: Huber-robust Levenberg-Marquardt."""

from __future__ import annotations

import numpy as np
import pytest

from robot.vision._robust_lm import huber_residuals, minimise_huber


class TestHuberResiduals:
    def test_squares_are_twice_the_huber_cost(self) -> None:
        r = np.array([-3.0, -0.5, 0.0, 0.2, 4.0])
        k = 1.0
        psi, slope = huber_residuals(r, k)
        cost = np.where(np.abs(r) <= k, 0.5 * r**2, k * np.abs(r) - 0.5 * k**2)
        np.testing.assert_allclose(psi**2, 2.0 * cost)
        np.testing.assert_array_equal(np.sign(psi), np.sign(r))
        h = 1e-7
        np.testing.assert_allclose(slope, (huber_residuals(r + h, k)[0] - psi) / h, atol=1e-6)


class TestMinimiseHuber:
    def test_line_fit_ignores_gross_outliers(self, rng: np.random.Generator) -> None:
        x = np.linspace(0.0, 1.0, 50)
        y = 2.0 * x + 1.0 + rng.normal(0.0, 0.01, 50)
        y[::10] += 5.0  # five gross outliers

        def residuals(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return p[0] * x + p[1] - y, np.column_stack([x, np.ones_like(x)])

        p = minimise_huber(residuals, np.zeros(2), k=0.02)
        assert p == pytest.approx([2.0, 1.0], abs=0.02)
        plain = np.polyfit(x, y, 1)  # least squares is pulled far off
        assert abs(plain[1] - 1.0) > 0.5

    def test_too_few_residuals_returns_the_start(self) -> None:
        def residuals(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return np.array([p[0] - 1.0]), np.array([[1.0, 0.0, 0.0]])

        np.testing.assert_array_equal(minimise_huber(residuals, np.zeros(3), 1.0), np.zeros(3))
