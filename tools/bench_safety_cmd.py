"""``vmnav bench safety``'s command line (issue 17); the benchmark is :mod:`tools.bench.safety`."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from tools.harness.arg_types import SEED


def add_parser(bench_sub: argparse._SubParsersAction,  # type: ignore[type-arg]
               run: Callable[[argparse.Namespace], int]) -> None:
    """Register ``vmnav bench safety``; ``run`` runs it (imported when it runs)."""
    safety = bench_sub.add_parser(
        "safety",
        help="issue 17: obstacle scenarios, people walking into the route, the emergency "
             "stop, the safety layer's cost",
        description="Run the safety scenarios (a person crossing, standing 10 s and 90 s, "
        "walking towards the robot, a box on the route, a bin beside it, a glass door the "
        "sonar misses) on the lab's short route; repeat the demo's mission per world and "
        "seed with people who do not avoid the robot and without them (contacts the robot "
        "caused, goals reached, lateral RMS, distance driven without verified localization, "
        "from the simulator's truth); time emergency stops on the hardware-in-the-loop rig; "
        "time the safety layer per frame. Prints JSON; progress on stderr.")
    safety.add_argument("--config", metavar="FILE", help="vmnav TOML config file")
    safety.add_argument("--calibration", metavar="FILE",
                        help="camera calibration JSON [default: 800x600, 185 deg]")
    safety.add_argument("--worlds", nargs="+", default=["lab", "campus"], metavar="WORLD",
                        help="worlds of the people runs [default: lab campus]")
    safety.add_argument("--seed", type=SEED, default=1, help="first seed [default: 1]")
    safety.add_argument("--seeds", type=int, default=20, metavar="N",
                        help="seeds per world of the people runs [default: 20]")
    safety.add_argument("--people", type=int, default=5, metavar="N",
                        help="people walking in the people runs [default: 5]")
    safety.add_argument("--estops", type=int, default=20, metavar="N",
                        help="emergency stops timed [default: 20]")
    safety.add_argument("--parts", nargs="+", default=["scenarios", "people", "e_stop",
                                                        "governor"],
                        choices=["scenarios", "people", "e_stop", "governor"],
                        help="parts to run [default: all four]")
    safety.add_argument("--out", type=Path, default=Path("out/bench_safety"), metavar="DIR",
                        help="where memories and rigs live [default: out/bench_safety]")
    safety.set_defaults(run=run)
