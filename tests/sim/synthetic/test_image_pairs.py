"""Tests of sim/synthetic/image_pairs.py: textured pairs with a known homography."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from shared.errors import ShapeError
from sim.synthetic.image_pairs import similarity_homography, texture, transform_pixels, warped_pair


class TestTexture:
    def test_smoke_and_determinism(self) -> None:
        a = texture(np.random.default_rng(0), 80, 60)
        b = texture(np.random.default_rng(0), 80, 60)
        assert a.shape == (60, 80) and a.dtype == np.float32
        np.testing.assert_array_equal(a, b)
        assert a.std() > 20.0


class TestSimilarityHomography:
    def test_known_answer(self) -> None:
        H = similarity_homography((3.0, -2.0), np.radians(90.0), 2.0, centre_xy=(10.0, 20.0))
        # The centre moves by the shift only; a point 1 px right of it turns to 2 px below.
        pixels = transform_pixels(H, np.array([[10.0, 20.0], [11.0, 20.0]]))
        np.testing.assert_allclose(pixels, [[13.0, 18.0], [13.0, 20.0]], atol=1e-12)

    def test_tilt_is_the_bottom_row(self) -> None:
        H = similarity_homography((0.0, 0.0), tilt=(1e-3, -2e-3))
        np.testing.assert_array_equal(H[2], [1e-3, -2e-3, 1.0])


class TestTransformPixels:
    def test_shape_errors(self) -> None:
        with pytest.raises(ShapeError, match="H_b_a"):
            transform_pixels(np.eye(2), np.zeros((1, 2)))
        with pytest.raises(ShapeError, match="pixels_a_xy"):
            transform_pixels(np.eye(3), np.zeros((1, 3)))

    def test_empty(self) -> None:
        assert transform_pixels(np.eye(3), np.zeros((0, 2))).shape == (0, 2)


class TestWarpedPair:
    def test_image_b_sees_image_a_through_the_homography(self) -> None:
        H = similarity_homography((4.5, -3.25), np.radians(3.0), 1.05, centre_xy=(80.0, 60.0))
        pair = warped_pair(np.random.default_rng(1), H, 160, 120,
                           noise_sigma=0.0, gain=0.5, offset=30.0)
        assert pair.image_a.shape == pair.image_b.shape == (120, 160)
        assert pair.image_a.dtype == pair.image_b.dtype == np.uint8
        # Sample A where B's interior pixels come from: B(p_b) = 0.5 A(H^-1 p_b) + 30.
        rows, cols = np.mgrid[20:100, 20:140]
        pixels_b = np.column_stack([cols.ravel(), rows.ravel()]).astype(np.float64)
        pixels_a = transform_pixels(np.linalg.inv(H), pixels_b).astype(np.float32)
        seen = cv2.remap(pair.image_a.astype(np.float32), pixels_a[:, 0].reshape(rows.shape),
                         pixels_a[:, 1].reshape(rows.shape), cv2.INTER_LINEAR)
        residual = pair.image_b[20:100, 20:140].astype(np.float64) - (0.5 * seen + 30.0)
        # Rounding, clipping and interpolating a quantised image leave a small residual.
        assert np.median(np.abs(residual)) < 1.0

    def test_noise(self) -> None:
        rng = np.random.default_rng(2)
        pair = warped_pair(rng, np.eye(3), 160, 120, noise_sigma=3.0)
        difference = pair.image_b.astype(np.float64) - pair.image_a
        assert 3.0 < difference.std() < 5.0  # two independent noises: sqrt(2) * 3
