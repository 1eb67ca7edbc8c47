"""``vmnav bench follow`` and ``vmnav bench sweep``'s command lines: both run through the sweep
(:mod:`tools.sweep`); the benchmarks are :mod:`tools.bench.follow` and :mod:`tools.bench.sweep`.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from tools.harness.arg_types import KEY_IMAGE, POSITIVE, POSITIVE_COUNT
from tools.harness.scene_args import add_change_arguments
from tools.harness.sim_args import add_sim_arguments


def add_parsers(bench_sub: argparse._SubParsersAction,  # type: ignore[type-arg]
                follow_run: Callable[[argparse.Namespace], int],
                sweep_run: Callable[[argparse.Namespace], int]) -> None:
    """Register ``vmnav bench follow`` and ``vmnav bench sweep``; the ``run`` functions run
    them (imported when they run)."""
    follow = bench_sub.add_parser(
        "follow",
        help="route following: seeded demos without video, laws side by side",
        description="For each seed, teach the demo's routes (cached in OUT/seed<N>) and repeat "
        "the demo's mission once per control law; print per-seed rows and an aggregate per "
        "law (goal reached, final position error, lateral and heading errors on ground truth). "
        "A small plan run through the sweep (docs/sweeps.md), on --workers processes.",
    )
    add_sim_arguments(follow)
    follow.add_argument("--seeds", type=int, default=20, metavar="N",
                        help="number of seeds, from --seed on [default: 20]")
    follow.add_argument("--laws", nargs="+", default=["paper", "paper+ff"], metavar="LAW",
                        help="control laws to compare [default: paper paper+ff]")
    follow.add_argument("--max-omega-deg", type=POSITIVE, default=None, metavar="DEG",
                        help="turn-rate bound, deg/s [default: the config's, 25]")
    follow.add_argument("--routes", nargs="+", metavar="NAME", help="routes [default: the demo's]")
    follow.add_argument("--goal", type=KEY_IMAGE, metavar="ID", help="goal [default: the demo's]")
    add_change_arguments(follow)
    follow.add_argument("--out", type=Path, default=Path("out/bench_follow"), metavar="DIR",
                        help="where the seeds' memories are cached [default: out/bench_follow]")
    follow.add_argument("--workers", type=POSITIVE_COUNT, default=None, metavar="N",
                        help="processes the runs are spread over (1: this process) [default: "
                        "one per CPU, at most one per run]")
    follow.set_defaults(run=follow_run)
    sweep = bench_sub.add_parser(
        "sweep",
        help="issue 20: a plan of short cases on 1 and 2 local workers and on Ray, side by side",
        description="Teach the memories of a plan of short cases (the lab's 2.5 m route "
        "east_a; seeds x laws x light) once, then run its cases on a pool of 1 process, a "
        "pool of 2 and a local Ray with 2 CPUs, one after the other; print JSON: each run's "
        "wall time and the workers' peak memory, the speed-ups, and whether the three gave "
        "identical figures per case (the wall-clock ones aside). About 12 min at the defaults "
        "on 2 idle cores.",
    )
    sweep.add_argument("--cases", type=POSITIVE_COUNT, default=20, metavar="N",
                       help="cases of the plan, a multiple of 4 (seeds x 2 laws x 2 light "
                       "levels) [default: 20]")
    sweep.add_argument("--no-ray", action="store_true", help="leave Ray out")
    sweep.add_argument("--out", type=Path, default=Path("out/bench_sweep"), metavar="DIR",
                       help="the taught memories [default: out/bench_sweep]")
    sweep.set_defaults(run=sweep_run)
