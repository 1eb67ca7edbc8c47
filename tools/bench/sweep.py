"""``vmnav bench sweep``: one plan of short cases on 1 and 2 local workers and on a local Ray,
side by side (issue 20's numbers).

The plan: the lab with its 2.5 m route ``east_a`` (:mod:`tools.harness.short_routes`),
taught per seed, repeated from the demo's offset to the route's end; seeds x the two
laws x the light as taught or at 70 %. The memories are taught first (on every CPU, not
timed: the runs compare the cases' parallelism), then the same cases run on each
executor in turn, timed on the wall clock. Printed: each run's wall time and per-case
mean, the workers' peak resident memory, the speed-ups, and whether every case gave the
same figures on every executor (the wall-clock figures aside).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import wait
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shared.errors import InputError

if TYPE_CHECKING:
    from tools.sweep.executors import Executor
    from tools.sweep.plan import Case, SweepPlan

#: What marks a folder as this benchmark's (it writes only into its own or a new one).
MARK = "bench_sweep.json"
#: Issue 20's numbers: figure -> (comparison, bound). Ray "within 15 %" of the pool: no
#: slower than 1.15 times its wall time (faster is fine).
TARGETS: dict[str, tuple[str, float]] = {
    "runs.pool_2.speedup_vs_pool_1": (">=", 1.7),
    "runs.ray_local_2.wall_vs_pool_2": ("<=", 1.15),
    "identical_figures": (">=", 1),
    "runs.pool_2.worker_peak_rss_mb_max": ("<", 1536),
    "runs.ray_local_2.worker_peak_rss_mb_max": ("<", 1536),
}


def short_plan(world_file: Path, cases: int) -> SweepPlan:
    """``cases / 4`` seeds x the two laws x light 100 % or 70 %, on ``east_a`` of
    ``world_file``."""
    from tools.sweep.plan import SweepPlan

    return SweepPlan(axes=(("world", (str(world_file),)),
                           ("seed", tuple(range(1, cases // 4 + 1))),
                           ("lighting", (None, "scale=0.7")),
                           ("law", ("paper", "paper+ff"))),
                     routes=("east_a",), source="vmnav bench sweep")


def timed_run(cases: list[Case], out: Path, executor: Executor) -> tuple[float, list[dict[str,
                                                                                       Any]]]:
    """Run ``cases`` on ``executor`` (then close it): wall time, s, and the rows."""
    from tools.sweep.results import code_version
    from tools.sweep.runner import outcome_text, run_sweep

    def line(case: Case, row: dict[str, Any]) -> None:
        print(f"vmnav bench sweep: {executor.description}: {case.case_id}: "
              f"{outcome_text(row)}", file=sys.stderr, flush=True)

    started = time.perf_counter()
    try:
        rows = run_sweep(cases, lambda case: out / case.memory_name, executor, None,
                         code_version(), line, "bench sweep")
    finally:
        executor.close()
    return time.perf_counter() - started, rows


def figures_differ(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> list[str]:
    """The (case, figure) pairs that differ between two runs of the same cases, the
    wall-clock figures aside."""
    from tools.sweep.results import FIGURES, TIMING

    return [f"{x['case_id']}: {key} {x.get(key)!r} != {y.get(key)!r}"
            for x, y in zip(a, b, strict=True)
            for key in ("status", *FIGURES) if key not in TIMING and x.get(key) != y.get(key)]


def summary(wall_s: float, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """One run's figures."""
    return {"wall_s": round(wall_s, 1),
            "case_wall_s_mean": round(sum(float(r.get("wall_time_s") or 0) for r in rows)
                                      / len(rows), 2),
            "crashed": sum(r["status"] != "ok" for r in rows),
            "reached": sum(bool(r.get("reached_goal")) for r in rows),
            "worker_peak_rss_mb_max": max(float(r["worker_peak_rss_mb"]) for r in rows)}


def run(args: argparse.Namespace) -> int:
    """Print the benchmark's JSON (see the module docstring)."""
    from tools.harness.short_routes import write_short_routes_world
    from tools.sweep.case import teach_task
    from tools.sweep.executors import PoolExecutor, RayExecutor, cpu_count
    from tools.sweep.plan_check import check_plan

    if args.cases % 4:
        raise InputError("--cases", f"must be a multiple of 4, got {args.cases}")
    out: Path = args.out
    if out.exists() and any(out.iterdir()) and not (out / MARK).exists():
        raise InputError(out, "holds files this benchmark did not write: choose another --out")
    out.mkdir(parents=True, exist_ok=True)
    (out / MARK).write_text(json.dumps({"benchmark": "sweep"}) + "\n")
    plan = short_plan(write_short_routes_world(out), args.cases)
    check_plan(plan)
    cases = plan.cases()
    load_start = os.getloadavg()
    started = time.perf_counter()
    teacher = PoolExecutor(cpu_count())
    memories = {case.memory_name: case.run_memory_argv for case in cases}
    taught = [teacher.submit(teach_task, argv, out / name, 1)
              for name, argv in memories.items()]
    wait(taught)
    teacher.close()
    failed = [f.result()["error"] for f in taught if f.result()["status"] != "ok"]
    if failed:
        raise InputError("teaching", failed[0].strip().splitlines()[-1])
    teach_s = time.perf_counter() - started
    runs: dict[str, Any] = {}
    one_s, one = timed_run(cases, out, PoolExecutor(1))
    runs["pool_1"] = summary(one_s, one)
    two_s, two = timed_run(cases, out, PoolExecutor(2))
    runs["pool_2"] = {**summary(two_s, two), "speedup_vs_pool_1": round(one_s / two_s, 2)}
    differences = figures_differ(one, two)
    if not args.no_ray:
        ray_started = time.perf_counter()
        executor = RayExecutor("local", 2)
        ray_init_s = time.perf_counter() - ray_started
        ray_s, on_ray = timed_run(cases, out, executor)
        runs["ray_local_2"] = {**summary(ray_s, on_ray), "init_s": round(ray_init_s, 1),
                               "wall_vs_pool_2": round(ray_s / two_s, 3)}
        differences += figures_differ(one, on_ray)
    print(json.dumps({
        "benchmark": "sweep", "cases": len(cases), "memories": len(memories),
        "plan": plan.to_dict(), "cpus": cpu_count(),
        "load_average_1min": {"start": round(load_start[0], 2),
                              "end": round(os.getloadavg()[0], 2)},
        "teach_wall_s": round(teach_s, 1), "runs": runs,
        "identical_figures": not differences, "differences": differences[:20]}, indent=2))
    return 0
