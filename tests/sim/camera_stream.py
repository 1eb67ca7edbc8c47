"""Numbered frames for the network camera's tests, and a thread publishing them."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np
import numpy.typing as npt

from sim.camera_server import CameraServer

SHAPE = (120, 160)
"""(H, W) of the numbered frames: small, so JPEG and decoding are quick."""
_NUMBERS = 20


def numbered_frame(k: int, shape: tuple[int, int] = SHAPE) -> npt.NDArray[np.uint8]:
    """A grey frame whose mean level tells ``k`` modulo 20 apart after JPEG.

    It is textured (zero-mean noise of +-12 levels, the same in every frame): FFmpeg
    opens a stream once it has probed about 2 kB, which a flat frame's JPEG is not.
    """
    texture = np.random.default_rng(0).integers(-12, 13, shape)
    return (20 + 10 * (k % _NUMBERS) + texture).astype(np.uint8)


def frame_number(image: npt.NDArray[np.uint8]) -> int:
    """``k`` modulo 20 of a decoded :func:`numbered_frame`."""
    return round((float(image.mean()) - 20) / 10) % _NUMBERS


@contextmanager
def publishing(server: CameraServer, period_s: float = 0.02,
               shape: tuple[int, int] = SHAPE) -> Iterator[list[int]]:
    """Publish numbered frames 0, 1, ... on ``server`` every ``period_s`` (frame time
    k * period) from a thread; yields the list of numbers published so far."""
    published: list[int] = []
    stop = threading.Event()

    def run() -> None:
        k = 0
        while True:
            server.publish(round(k * period_s * 1e9), numbered_frame(k, shape))
            published.append(k)
            k += 1
            if stop.wait(period_s):
                return

    thread = threading.Thread(target=run, name="publisher")
    thread.start()
    try:
        yield published
    finally:
        stop.set()
        thread.join()


def eventually(condition: Callable[[], bool], timeout_s: float = 5.0) -> bool:
    """Whether ``condition()`` holds within ``timeout_s`` (polled every 10 ms): for what
    another thread does in its own time."""
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            return False
        time.sleep(0.01)
    return True
