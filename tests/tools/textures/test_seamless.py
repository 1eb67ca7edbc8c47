"""Making photographs tile, and measuring seams."""

from __future__ import annotations

import numpy as np

from sim.procedural_textures import periodic_noise
from tools.textures.seamless import make_seamless, seam_ratio


def _photo_like(rng: np.random.Generator) -> np.ndarray:
    """Smooth texture plus a gradient: its wrap-around shows a strong seam."""
    noise = periodic_noise((200, 300), 3.0, rng)
    y, x = np.mgrid[0:200, 0:300]
    image = 128 + 25 * noise + 0.3 * x - 0.2 * y
    return np.clip(image, 0, 255).astype(np.uint8)


class TestMakeSeamless:
    def test_removes_the_seam_of_a_photograph(self, rng: np.random.Generator) -> None:
        photo = _photo_like(rng)
        assert seam_ratio(photo) > 2.0
        seamless = make_seamless(photo)
        assert seamless.shape == photo.shape and seamless.dtype == np.uint8
        assert seam_ratio(seamless) < 1.0

    def test_keeps_the_middle_and_the_contrast(self, rng: np.random.Generator) -> None:
        photo = _photo_like(rng)
        seamless = make_seamless(photo, band=0.25)
        # Outside the blend band the original is untouched.
        np.testing.assert_array_equal(seamless[60:140, 80:220], photo[60:140, 80:220])
        # The blend keeps the fine texture's contrast (no washed-out band).
        band = seamless[:, 30:50].astype(float)
        assert np.abs(np.diff(band, axis=0)).mean() > 0.7 * np.abs(
            np.diff(photo[:, 30:50].astype(float), axis=0)).mean()


class TestSeamRatio:
    def test_a_periodic_texture_scores_at_most_one(self, rng: np.random.Generator) -> None:
        noise = np.clip(128 + 30 * periodic_noise((128, 128), 2.0, rng), 0, 255).astype(np.uint8)
        assert seam_ratio(noise) <= 1.0

    def test_a_line_on_the_border_is_no_seam(self) -> None:
        # Grout on the border is as abrupt as grout inside: ratio 1, not a seam.
        image = np.full((64, 64), 200, np.uint8)
        image[:, 0:2] = 80
        image[:, 32:34] = 80
        assert seam_ratio(image) <= 1.0

    def test_a_step_at_the_wrap_is_a_seam(self) -> None:
        image = np.tile(np.linspace(50, 200, 64).astype(np.uint8), (64, 1))
        assert seam_ratio(image) > 10.0
