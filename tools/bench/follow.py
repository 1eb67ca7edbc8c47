"""``vmnav bench follow``: seeded demos without video, per seed and aggregated, laws side by side.

A small built-in plan run through the sweep (:mod:`tools.sweep`): the seeds and the laws
are its axes, the options its other values. Each seed teaches its own memory (cached in
``OUT/seed<N>``, see :func:`tools.harness.demo.taught_memory`) and repeats the demo's
mission once per control law on it, so the laws are compared on the same memories, start
and goal; the cases run on ``--workers`` processes (one: in this process). Each run's
figures are also printed on stderr as it ends (one line per seed and law).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from statistics import median
from typing import TYPE_CHECKING

from shared.errors import InputError

if TYPE_CHECKING:
    from tools.sweep.plan import Case, SweepPlan

#: Report fields kept per seed (the events stay out of the benchmark's JSON).
SEED_KEYS = ("reached_goal", "reason", "final_position_error_m", "lateral_rms_m",
             "lateral_max_m", "heading_rms_deg", "key_images_route", "key_images_reached",
             "distance_m", "sim_time_s", "wall_time_s", "mean_matches", "loop_ms_p50",
             "loop_ms_p95", "lost_events", "scene_change")


def follow_plan(args: argparse.Namespace, first_seed: int) -> SweepPlan:
    """The plan of ``vmnav bench follow``'s options: seeds and laws as axes, the world,
    camera, people and scene change as one-value axes."""
    from tools.sweep.plan import SweepPlan

    axes: list[tuple[str, tuple[object, ...]]] = [
        ("world", (args.world,)), ("seed", tuple(range(first_seed, first_seed + args.seeds))),
        ("people", (args.people,)), ("lighting", (args.lighting,)),
        ("moved", (args.moved or None,)), ("removed", (args.removed,)),
        ("doors", (args.doors,)), ("calibration", (args.calibration,)),
        ("law", tuple(args.laws))]
    return SweepPlan(axes=tuple(axes), routes=tuple(args.routes) if args.routes else None,
                     goal_id=args.goal, config=args.config, max_omega_deg=args.max_omega_deg,
                     source="vmnav bench follow")


def bench_follow(plan: SweepPlan, out: Path, workers: int) -> dict[str, object]:
    """Run the plan (memories in ``out/seed<N>``); per-seed rows and an aggregate per law.

    Raises:
        InputError: a case crashed (the first, with its error's last line).
    """
    from tools.sweep.executors import Executor, InlineExecutor, PoolExecutor
    from tools.sweep.results import code_version
    from tools.sweep.runner import outcome_text, run_sweep

    cases = plan.cases()
    workers = min(workers, len(cases))
    executor: Executor = InlineExecutor() if workers == 1 else PoolExecutor(workers)

    def line(case: Case, row: dict[str, object]) -> None:
        print(f"vmnav bench follow: seed {row['seed']} {row['law']}: {outcome_text(row)}",
              file=sys.stderr, flush=True)

    try:
        found = run_sweep(cases, lambda case: out / f"seed{dict(case.values)['seed']}",
                          executor, None, code_version(), line, "bench follow")
    finally:
        executor.close()
    for row in found:
        if row["status"] != "ok":
            lines = str(row["error"]).strip().splitlines()
            raise InputError(f"seed {row['seed']} {row['law']}", lines[-1])
    rows = [{"seed": row["seed"], "law": row["law"], "goal_key_image": row["goal_key_image"],
             **{key: row[key] for key in SEED_KEYS}} for row in found]
    laws = dict(plan.axes)["law"]
    return {"seeds": rows, "aggregate": {law: aggregate([r for r in rows if r["law"] == law])
                                         for law in laws}}


def aggregate(rows: list[dict[str, object]]) -> dict[str, object]:
    """Reached count; worst and median errors over the seeds (None-valued entries skipped)."""

    def values(key: str) -> list[float]:
        return [float(v) for r in rows if isinstance(v := r[key], int | float)
                and not isinstance(v, bool)]

    def stat(fn: Callable[[list[float]], float], key: str) -> float | None:
        found = values(key)
        return round(fn(found), 4) if found else None

    return {
        "runs": len(rows),
        "reached_goal": sum(bool(r["reached_goal"]) for r in rows),
        "final_position_error_m_max": stat(max, "final_position_error_m"),
        "lateral_rms_m_median": stat(median, "lateral_rms_m"),
        "lateral_rms_m_max": stat(max, "lateral_rms_m"),
        "lateral_max_m_max": stat(max, "lateral_max_m"),
        "heading_rms_deg_max": stat(max, "heading_rms_deg"),
        "loop_ms_p50_median": stat(median, "loop_ms_p50"),
        "lost_events": round(sum(values("lost_events"))),
    }


def run(args: argparse.Namespace) -> int:
    """Print the route-following benchmark's JSON (``vmnav bench follow``)."""
    from robot.config import CONTROL_LAWS
    from tools.harness.scene_args import scene_change_from_args
    from tools.harness.sim_args import sim_config_from_args
    from tools.sweep.executors import cpu_count
    from tools.sweep.plan_check import check_plan

    if args.seeds < 1:
        raise InputError("--seeds", f"must be >= 1, got {args.seeds}")
    for law in args.laws:
        if law not in CONTROL_LAWS:
            raise InputError("--laws", f"unknown law {law!r} (known: {', '.join(CONTROL_LAWS)})")
    scene_change_from_args(args)
    sim_config, _ = sim_config_from_args(args)
    plan = follow_plan(args, sim_config.seed)
    check_plan(plan)
    result = bench_follow(plan, args.out, args.workers or cpu_count())
    print(json.dumps({"benchmark": "follow", **result}, indent=2))
    return 0
