"""``vmnav bench web``'s command line (issue 18); the benchmark is :mod:`tools.bench.web`."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from tools.harness.arg_types import POSITIVE, POSITIVE_COUNT


def add_parser(bench_sub: argparse._SubParsersAction,  # type: ignore[type-arg]
               run: Callable[[argparse.Namespace], int]) -> None:
    """Register ``vmnav bench web``; ``run`` runs it (imported when it runs)."""
    web = bench_sub.add_parser(
        "web",
        help="issue 18: the web app in headless Chromium: telemetry to the page, goto to "
             "its reply, a fleet of 20 vehicles, the first load, the camera",
        description="Serve the web app with vehicles of the link bench's load generator on "
        "loopback and open it in headless Chromium: time a vehicle's mode change to the "
        "page's DOM, the page's goto to its reply (after MISSION_ACK), the main-thread time "
        "of each fleet update and this process's CPU, the first load's bytes and time "
        "to interactive, and the camera (vehicle 1 serving the robot's live view at 640x480): "
        "frames/s shown in the page and their latency, read back from numbers drawn into "
        "the frames. Prints JSON. About 45 s.")
    web.add_argument("--vehicles", type=POSITIVE_COUNT, default=20, metavar="N",
                     help="vehicles in the fleet [default: 20]")
    web.add_argument("--changes", type=POSITIVE_COUNT, default=30, metavar="N",
                     help="mode changes timed [default: 30]")
    web.add_argument("--dispatches", type=POSITIVE_COUNT, default=30, metavar="N",
                     help="goto requests timed [default: 30]")
    web.add_argument("--key-images", type=POSITIVE_COUNT, default=100, metavar="N",
                     help="key images each vehicle knows [default: 100]")
    web.add_argument("--camera-hz", type=POSITIVE, default=15.0, metavar="HZ",
                     help="the live view's frame rate (the robot's [video] frame_period_ns) "
                     "[default: 15]")
    web.add_argument("--camera-s", type=POSITIVE, default=10.0, metavar="S",
                     help="how long the camera is watched, s [default: 10]")
    web.set_defaults(run=run)
