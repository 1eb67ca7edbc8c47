"""``vmnav bench web``'s camera: the frame numbers survive the robot's JPEG encoding, and
the figures from what the page noted (the page itself runs in ``vmnav bench web``)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from robot.config import VideoConfig
from tools.bench.web_camera import BITS, BLOCK_H, BLOCK_W, SIZE, camera_figures, numbered_frame


def read_number(image: np.ndarray) -> int:
    """The number as the page's sampler reads it (block centres, > 127 is 1)."""
    n = 0
    for b in range(BITS):
        n = n * 2 + int(image[BLOCK_H // 2, b * BLOCK_W + BLOCK_W // 2] > 127)
    return n


@pytest.mark.parametrize("number", [0, 1, 0x5A5A, (1 << BITS) - 1])
def test_the_number_survives_the_live_views_jpeg(number: int) -> None:
    texture = np.random.default_rng(0).integers(60, 200, SIZE[::-1]).astype(np.uint8)
    frame = numbered_frame(number, texture)
    assert frame.shape == (480, 640) and np.array_equal(frame[BLOCK_H:], texture[BLOCK_H:])
    ok, jpeg = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, VideoConfig().jpeg_quality])
    assert ok
    assert read_number(cv2.imdecode(jpeg, cv2.IMREAD_GRAYSCALE)) == number


def test_figures_from_what_the_page_noted() -> None:
    sent = {1: 1000.0, 2: 1100.0, 3: 1200.0}
    shown = [[1, 1050.0], [2, 1160.0], [999, 1170.0], [3, 1250.0]]
    figures = camera_figures(shown, sent, 5.0)
    assert figures["frames_shown"] == 3 and figures["misread"] == 1
    assert figures["shown_fps"] == 10.0  # 2 intervals in 0.2 s
    assert figures["latency_ms"] == {"n": 3, "median": 50.0, "p95": 60.0, "max": 60.0}
    assert camera_figures([], sent, 5.0)["shown_fps"] == 0.0
