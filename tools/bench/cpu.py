"""Pinning a benchmark to one core, so its timings do not depend on free cores."""

from __future__ import annotations

import os


def pin_to_one_core() -> list[int]:
    """Pin this process to one CPU, with one OpenCV thread, one BLAS thread and one
    rendering thread; returns the CPU set.

    The BLAS limit matters: OpenBLAS starts one thread per CPU when numpy is imported,
    and its threads spin while they wait, so two of them sharing the pinned CPU made a
    localization among 300 key images (its prefilter's matrix product) take 330 ms
    instead of 8 ms.
    """
    import cv2
    from threadpoolctl import threadpool_limits

    from sim.renderer import set_render_threads

    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    cv2.setNumThreads(1)
    threadpool_limits(limits=1)
    set_render_threads(1)
    return sorted(os.sched_getaffinity(0))
