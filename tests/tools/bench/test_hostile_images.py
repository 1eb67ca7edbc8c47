"""The image bombs are what they claim to be, and the benchmark measures them."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from tools.bench.hostile_images import bogus_chunk_png, header_bomb_png, large_png, measure


def test_large_png_is_a_valid_black_image() -> None:
    # The repeated-block zlib stream and its Adler-32 are right: OpenCV decodes it whole.
    image = cv2.imdecode(np.frombuffer(large_png(1000), np.uint8), cv2.IMREAD_UNCHANGED)
    assert image.shape == (1000, 1000) and not image.any()
    assert len(large_png()) < 1_000_000


def test_the_small_bombs_are_small() -> None:
    assert len(header_bomb_png()) < 100
    assert len(bogus_chunk_png(np.random.default_rng(0))) < 3384


@pytest.mark.slow
def test_measure_refuses_every_bomb_and_accepts_the_photo() -> None:
    figures = measure()
    assert figures["targets_met"] is True
    for name in ("header_bomb", "bogus_chunk", "large_png"):
        bomb = figures[name]
        assert isinstance(bomb, dict) and bomb["refused"] and not bomb["found"]
    assert figures["valid_photo_accepted"] is True
