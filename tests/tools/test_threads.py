"""tools.threads: the demo's repeat leaves a CPU to the processes beside it, and never
computes on more threads than were set."""

from __future__ import annotations

import os

import numba
import pytest

from tools.threads import compute_threads, leave_a_cpu


@pytest.fixture
def restore_threads():
    before = numba.get_num_threads()
    yield
    compute_threads(before)


def test_leave_a_cpu_takes_one_from_all_and_never_adds(restore_threads) -> None:
    started = numba.config.NUMBA_NUM_THREADS  # numba's pool: at most one per CPU by default
    compute_threads(started)
    leave_a_cpu()
    assert numba.get_num_threads() == max(1, min(started, len(os.sched_getaffinity(0)) - 1))
    compute_threads(1)
    leave_a_cpu()
    assert numba.get_num_threads() == 1
