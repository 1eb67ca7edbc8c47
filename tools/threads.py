"""The threads a vmnav process computes with: one BLAS thread.

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
