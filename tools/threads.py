"""The threads a vmnav process computes with: one BLAS thread, and fewer render and OpenCV
threads where processes share the CPUs.

OpenBLAS (numpy, scipy and OpenCV each load their own copy) starts one thread per CPU
and its threads spin while they wait for work. vmnav's matrix products are small (a
key-image prefilter of a few hundred rows, 3 x 3 rotations of point sets), too small to
gain from threads, so those threads only burned CPU: ``vmnav demo`` cost 172 s of CPU
time in 70 s of wall time on 2 cores with them, 74 s with one.
"""

from __future__ import annotations

import os

from threadpoolctl import threadpool_limits

_BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """One thread for every BLAS library of this process and its children.

    The environment variables reach the libraries loaded from now on (OpenBLAS reads
    them when it loads) and child processes; those already loaded are limited at once.
    A variable the user set is kept.
    """
    for name in _BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    threadpool_limits(limits=1, user_api="blas")


def compute_threads(count: int) -> None:
    """Render on ``count`` threads and run OpenCV's parallel loops on as many.

    For processes that share the CPUs with others that compute (a sweep's workers, a
    parallel teach's, the test suite's): OpenCV's and numba's pools, like OpenBLAS's, wait
    actively for work, so a process's idle threads burn the CPU the others need (a test of
    a mission in lock-step: 38 s of CPU on two threads each, 35 s on one, medians of 3; the
    short demo beside other processes: 42 s instead of 24).

    Raises:
        ValueError: ``count`` is below 1 or above the threads numba started.
    """
    import cv2

    from sim.renderer import set_render_threads

    set_render_threads(count)
    cv2.setNumThreads(count)


def leave_a_cpu() -> None:
    """Compute on every CPU this process may use but one, or on fewer if fewer were set
    (:func:`compute_threads`; never more): for a lock-step simulation with a helper
    process beside it, such as the demo's video encoder.
    """
    import numba

    cpus = len(os.sched_getaffinity(0))
    compute_threads(max(1, min(numba.get_num_threads(), cpus - 1)))
