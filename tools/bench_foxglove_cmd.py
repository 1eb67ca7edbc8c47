"""``vmnav bench foxglove``'s command line (issue 18): :mod:`tools.bench.foxglove`."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from tools.harness.arg_types import POSITIVE


def add_parser(bench_sub: argparse._SubParsersAction,  # type: ignore[type-arg]
               run: Callable[[argparse.Namespace], int]) -> None:
    """Register ``vmnav bench foxglove``; ``run`` runs it (imported when it runs)."""
    foxglove = bench_sub.add_parser(
        "foxglove",
        help="issue 18: the live topics' cost on the robot's loop per frame, without a "
             "viewer, with one, with one that stalls",
        description="Feed `vmnav robot --foxglove`'s bridge 800x600 frames and following "
        "cycles at a camera's rate, as the robot's loop does, with no viewer, a viewer "
        "reading every topic, and a viewer that never reads; print per phase the loop's "
        "time in the bridge per frame (p50, p99, max), the process's CPU and what the viewer "
        "received. About 4 x --seconds.")
    foxglove.add_argument("--seconds", type=POSITIVE, default=5.0, metavar="S",
                          help="length of each phase, s [default: 5]")
    foxglove.add_argument("--rate-hz", type=POSITIVE, default=30.0, metavar="HZ",
                          help="frames per second [default: 30]")
    foxglove.set_defaults(run=run)
