"""Worker: the loop never waits on a job, except in lock-step, where it waits at once."""

from __future__ import annotations

import logging
import threading

from robot.mode_events import PathNotStored, PhotoNotFound
from robot.worker import Worker


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
