"""The local pool: a worker that dies fails its task, and the pool goes on with a new one."""

from __future__ import annotations

import os
from concurrent.futures.process import BrokenProcessPool

import pytest

from tools.sweep.executors import PoolExecutor


def test_a_dead_worker_fails_its_task_and_the_next_task_runs() -> None:
    pool = PoolExecutor(1)
    try:
        dead = pool.submit(os._exit, 3)  # the worker process exits at once, as if killed
        with pytest.raises(BrokenProcessPool):
            dead.result(timeout=120)
        pid = pool.submit(os.getpid).result(timeout=120)
        assert pid != os.getpid()
    finally:
        pool.close()
