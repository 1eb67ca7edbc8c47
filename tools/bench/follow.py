"""``vmnav bench follow``: seeded demos without video, per seed and aggregated, laws side by side.

Each run's figures are also printed on stderr as it ends (one line per seed and law).

Each seed teaches its own memory (cached in ``OUT/seed<N>``, see
:func:`tools.harness.demo.taught_memory`) and repeats the demo's mission once per control
law on it, so the laws are compared on the same memories, start and goal.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from statistics import median
from typing import TYPE_CHECKING

from tools.figures.demo_report import build_report
from tools.harness.demo import (
    default_goal,
    follow_config,
    repeat_in_sim,
    taught_memory,
)
from tools.harness.progress import Progress

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from shared.camera_model import CameraModel
    from sim.config import SimConfig
    from sim.scene_change import SceneChange

#: Report fields kept per seed (the events stay out of the benchmark's JSON).
SEED_KEYS = ("reached_goal", "reason", "final_position_error_m", "lateral_rms_m",
             "lateral_max_m", "heading_rms_deg", "key_images_route", "key_images_reached",
             "distance_m", "sim_time_s", "wall_time_s", "mean_matches", "loop_ms_p50",
             "loop_ms_p95", "lost_events", "scene_change")


@dataclass(frozen=True, slots=True)
class FollowBenchPlan:
    """What to run.

    Attributes:
        seeds: the simulation seeds.
        laws: control laws to compare (``robot.config.CONTROL_LAWS``).
        max_omega_deg: the turn-rate bound, deg/s (None: the config's).
        routes: routes taught per seed (None: all the world's, see
            :func:`tools.harness.demo.taught_memory`).
        goal_id: the goal key image (None: :func:`tools.harness.demo.default_goal`).
        change: what changed between each teach and its repeats (None: nothing; the
            people are the simulation config's).
    """

    seeds: tuple[int, ...]
    laws: tuple[str, ...]
    max_omega_deg: float | None
    routes: tuple[str, ...] | None = None
    goal_id: int | None = None
    change: SceneChange | None = None


def bench_follow(plan: FollowBenchPlan, out: Path, config: VmnavConfig,
                 sim_config: SimConfig, camera: CameraModel) -> dict[str, object]:
    """Run the plan; per-seed rows and an aggregate per law.

    Raises:
        InputError: bad routes, goal, bound or scene change (before or at the first seed).
    """
    from sim.scene_change import SceneChange

    change = plan.change or SceneChange()
    rows: list[dict[str, object]] = []
    with Progress("bench follow", len(plan.seeds) * len(plan.laws)) as bar:
        for seed in plan.seeds:
            seeded = replace(sim_config, seed=seed)
            bar.update(len(rows), f"seed {seed}: teaching")
            taught = taught_memory(out / f"seed{seed}", plan.routes, config, seeded, camera)
            goal = default_goal(taught) if plan.goal_id is None else plan.goal_id
            for law in plan.laws:
                bar.update(len(rows), f"seed {seed}: repeating with {law}")
                law_config = follow_config(config, law, plan.max_omega_deg)
                started = time.perf_counter()
                run = repeat_in_sim(taught, goal, law_config, seeded, change,
                                    out / f"seed{seed}")
                report = build_report(run, taught, law_config.control,
                                      time.perf_counter() - started)
                rows.append({"seed": seed, "law": law, "goal_key_image": goal,
                             **{key: report[key] for key in SEED_KEYS}})
                print(f"vmnav bench follow: seed {seed} {law}: {_seed_line(rows[-1])}",
                      file=sys.stderr, flush=True)
    return {"seeds": rows, "aggregate": {law: aggregate([r for r in rows if r["law"] == law])
                                         for law in plan.laws}}


def _seed_line(row: dict[str, object]) -> str:
    """One seed's figures in a line, e.g. ``reached, lateral RMS 1.4 cm, max 4.2 cm, ...``."""

    def cm(key: str) -> str:
        value = row[key]
        return "-" if not isinstance(value, int | float) else f"{100 * value:.1f} cm"

    outcome = "reached" if row["reached_goal"] else f"not reached ({row['reason']})"
    return (f"{outcome}, lateral RMS {cm('lateral_rms_m')}, max {cm('lateral_max_m')}, "
            f"final error {cm('final_position_error_m')}, {row['lost_events']} LOST, "
            f"{row['wall_time_s']} s")


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
    from robot.config import CONTROL_LAWS, load_config
    from shared.errors import InputError
    from tools.harness.scene_args import check_change_fits, scene_change_from_args
    from tools.harness.sim_args import sim_config_from_args

    if args.seeds < 1:
        raise InputError("--seeds", f"must be >= 1, got {args.seeds}")
    for law in args.laws:
        if law not in CONTROL_LAWS:
            raise InputError("--laws", f"unknown law {law!r} (known: {', '.join(CONTROL_LAWS)})")
    change = scene_change_from_args(args)
    sim_config, camera = sim_config_from_args(args)
    check_change_fits(change, sim_config)
    config = load_config(args.config)
    plan = FollowBenchPlan(
        seeds=tuple(range(sim_config.seed, sim_config.seed + args.seeds)), laws=tuple(args.laws),
        max_omega_deg=args.max_omega_deg,
        routes=tuple(args.routes) if args.routes else None, goal_id=args.goal,
        change=change)
    result = bench_follow(plan, args.out, config, sim_config, camera)
    print(json.dumps({"benchmark": "follow", **result}, indent=2))
    return 0
