"""What a sweep's worker runs: teach a memory, or repeat one case on a taught memory.

Both are plain functions of picklable data (options and folders), for a process pool or
Ray. Neither raises: a failure comes back as a row with its traceback, so that one case
that crashes is recorded and the sweep goes on.

A case's figures depend on its options only: the repeat reads its memory from the folder
the teach wrote (never a memory held in the teaching process), seeds every random draw
from the case's seed, and holds the simulation's clock while the ground station
dispatches (:func:`tools.harness.demo.repeat_in_sim`); only the wall-clock figures
(:data:`tools.sweep.results.TIMING`) differ from run to run.
"""

from __future__ import annotations

import resource
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any

from tools.sweep.results import FIGURES


def set_worker_threads(render_threads: int) -> None:
    """A worker's threads: ``render_threads`` for the renderer's rays and OpenCV, one for BLAS
    (a pool's initializer; Ray calls it at each task)."""
    from tools.threads import compute_threads, one_blas_thread

    one_blas_thread()
    compute_threads(render_threads)


def teach_task(memory_argv: tuple[str, ...], folder: Path, processes: int | None,
               render_threads: int | None = None) -> dict[str, Any]:
    """Teach the memory of ``memory_argv`` (``vmnav demo`` options) into ``folder`` (or find
    it there, taught before).

    Args:
        memory_argv: the options the memory depends on (world, seed, camera, routes, config).
        folder: the memory's folder (``folder/memory``, ``folder/teach.json``).
        processes: processes the routes are driven in (None: one per CPU).
        render_threads: set the worker's threads first (None: leave them).

    Returns:
        ``{"status": "ok", "teach_wall_time_s": s}`` or ``{"status": "crashed", "error":
        traceback}``.
    """
    started = time.perf_counter()
    try:
        if render_threads is not None:
            set_worker_threads(render_threads)
        from tools.harness.demo import taught_memory
        from tools.harness.repeat_args import parse_repeat_options, repeat_setup_from_args

        setup = repeat_setup_from_args(parse_repeat_options(memory_argv))
        folder.mkdir(parents=True, exist_ok=True)
        taught_memory(folder, setup.routes, setup.config, setup.sim_config, setup.camera,
                      processes)
    except Exception:
        return {"status": "crashed", "error": traceback.format_exc()}
    return {"status": "ok", "teach_wall_time_s": round(time.perf_counter() - started, 2)}


def case_task(argv: tuple[str, ...], folder: Path,
              render_threads: int | None = None) -> dict[str, Any]:
    """Repeat one case on the memory taught in ``folder`` (:func:`teach_task`).

    Args:
        argv: the case's ``vmnav demo`` options (:attr:`tools.sweep.plan.Case.argv`).
        folder: the memory's folder; the vehicle's files go to a temporary folder, so
            that cases of one memory run at once.
        render_threads: set the worker's threads first (None: leave them).

    Returns:
        The case's figures (:data:`tools.sweep.results.FIGURES` and
        :data:`~tools.sweep.results.SAFETY_FIGURES`, the simulator's truth of
        :mod:`tools.harness.safety_truth`) with ``status`` ``ok``, or ``crashed`` with
        ``error`` (the traceback); both with ``worker_peak_rss_mb``.
    """
    try:
        if render_threads is not None:
            set_worker_threads(render_threads)
        row = {"status": "ok", **_repeat(argv, folder)}
    except Exception:
        row = {"status": "crashed", "error": traceback.format_exc()}
    row["worker_peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                                      1)
    return row


def _repeat(argv: tuple[str, ...], folder: Path) -> dict[str, Any]:
    from tools.figures.demo_report import build_report
    from tools.harness.demo import default_goal, repeat_in_sim, taught_memory
    from tools.harness.repeat_args import parse_repeat_options, repeat_setup_from_args
    from tools.harness.safety_truth import judge, safety_figures
    from tools.harness.teach import TRUTH_NAME

    if not (folder / TRUTH_NAME).exists():  # a case never teaches: two could teach at once
        raise RuntimeError(f"{folder}: no memory taught there before the case")
    setup = repeat_setup_from_args(parse_repeat_options(argv))
    taught = taught_memory(folder, setup.routes, setup.config, setup.sim_config, setup.camera,
                           processes=1)
    goal = default_goal(taught) if setup.goal_id is None else setup.goal_id
    hook, truths = judge(setup.config)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="vmnav-case-") as vehicle:
        run = repeat_in_sim(taught, goal, setup.config, setup.sim_config, setup.change, folder,
                            on_sim=hook, start_offset_m=setup.start_offset_m,
                            vehicle_dir=Path(vehicle))
    report = build_report(run, taught, setup.config.control, time.perf_counter() - started)
    truths[0].finish()
    return {**{key: report[key] for key in FIGURES}, **safety_figures(truths[0], run)}
