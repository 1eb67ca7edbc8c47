"""Worker: the loop never waits on a job, except in lock-step, where it waits at once."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from robot.config import VmnavConfig
from robot.memory.localize import Localizer
from robot.mode_events import PathNotStored, PhotoNotFound
from robot.worker import Worker, find_photo
from shared.camera_model import CameraModel
from shared.memory import VisualMemory
from tools.bench.hostile_images import bogus_chunk_png, header_bomb_png


def slow_job(release: threading.Event, text: str) -> PathNotStored:
    release.wait(5.0)
    return PathNotStored(text)


def test_results_wait_for_nothing_and_keep_their_order() -> None:
    worker = Worker(lockstep=False)
    release = threading.Event()
    worker.submit(slow_job, release, "first")
    worker.submit(PhotoNotFound, logging.ERROR, "second")
    assert worker.results() == []  # the first job is still running: nothing yet
    release.set()
    got: list[object] = []
    for _ in range(500):
        got += worker.results()
        if len(got) == 2:
            break
        threading.Event().wait(0.01)
    assert got == [PathNotStored("first"), PhotoNotFound(logging.ERROR, "second")]
    worker.close()


def test_lockstep_waits_for_every_result_at_the_next_call() -> None:
    worker = Worker(lockstep=True)
    release = threading.Event()
    worker.submit(slow_job, release, "only")
    threading.Timer(0.05, release.set).start()
    assert worker.results() == [PathNotStored("only")]
    assert worker.results() == []
    worker.close()


@pytest.mark.parametrize(("bomb", "problem"), [
    (lambda: header_bomb_png(65535), "PNG of 65535x65535 px: a side is longer than 32768 px"),
    (lambda: bogus_chunk_png(np.random.default_rng(0)),
     "corrupt PNG: chunk tEXt at byte 33 declares 2147483647 bytes, the file has 3163 after "
     "its header"),
], ids=["beyond_opencv_cap", "bogus_chunk"])
def test_find_photo_refuses_a_bomb_with_a_notice(
        bomb: Callable[[], bytes], problem: str, tmp_path: Path) -> None:
    # Before the header check, OpenCV raised on the first (the worker's job failed) and
    # allocated 2 GB for the second.
    camera = CameraModel.default()
    config = VmnavConfig()
    localizer = Localizer.from_memory(VisualMemory(camera), config.camera.mount, config.features,
                                      config.localize)
    path = tmp_path / "7.png"
    path.write_bytes(bomb())
    assert find_photo(path, localizer, camera) == PhotoNotFound(
        logging.ERROR, f"photo 7.png: {problem}")
