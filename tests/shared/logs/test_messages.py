"""image_from_compressed: a logged camera frame back to grey, and hostile image data refused."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from shared.logs.messages import compressed_image, image_from_compressed
from tools.bench.hostile_images import bogus_chunk_png, large_png


def test_a_logged_frame_comes_back_grey() -> None:
    image = np.random.default_rng(0).integers(0, 256, (60, 80), dtype=np.uint8)
    png = cv2.imencode(".png", image)[1].tobytes()
    back, fmt = image_from_compressed(compressed_image(0, "camera", png, "png"))
    assert fmt == "png" and np.array_equal(back, image)


@pytest.mark.parametrize(("data", "problem"), [
    (bogus_chunk_png(np.random.default_rng(0)),
     "corrupt PNG: chunk tEXt at byte 33 declares 2147483647 bytes, the file has 3163 after "
     "its header"),
    (large_png(8192), "PNG of 8192x8192 px: 67108864 pixels, more than the 33554432 allowed"),
    (b"not an image", "not a PNG or JPEG image (the file starts with 6e 6f 74 20 61 6e 20 69)"),
], ids=["bogus_chunk", "large_png", "not_an_image"])
def test_hostile_image_data_is_refused_before_decoding(data: bytes, problem: str) -> None:
    with pytest.raises(ValueError) as caught:
        image_from_compressed(compressed_image(0, "camera", data, "png"))
    assert str(caught.value) == problem
