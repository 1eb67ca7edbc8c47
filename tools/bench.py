"""``vmnav bench ...``: benchmarks that print JSON (medians; one core)."""

from __future__ import annotations

import argparse
import json
import os

from tools.sim_args import add_sim_arguments, sim_config_from_args


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav bench`` and its benchmarks."""
    bench = subparsers.add_parser("bench", help="benchmarks printing JSON")
    bench_sub = bench.add_subparsers(dest="bench_command", metavar="BENCHMARK", required=True)
    sim = bench_sub.add_parser(
        "sim",
        help="simulator: physics + rendering frames/s, camera-model accuracy",
        description="Drive the simulated robot along a route and time physics + rendering per "
        "frame on one core; check the camera model's round trip and agreement with cv2.omnidir.",
    )
    add_sim_arguments(sim)
    sim.add_argument("--frames", type=int, default=300, help="frames to time [default: 300]")
    sim.set_defaults(run=run_sim)


def pin_to_one_core() -> list[int]:
    """Pin this process (and the threads OpenCV/BLAS start) to one CPU; returns the CPU set."""
    import cv2

    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    cv2.setNumThreads(1)
    return sorted(os.sched_getaffinity(0))


def run_sim(args: argparse.Namespace) -> int:
    """Print the simulator benchmark's JSON."""
    from sim.bench import bench_render, camera_accuracy, versions

    config, camera = sim_config_from_args(args)
    cpus = pin_to_one_core()
    result = {"benchmark": "sim", "cpus": cpus, **bench_render(config, camera, frames=args.frames)}
    result.update(camera_accuracy(camera))
    result["versions"] = versions()
    print(json.dumps(result, indent=2))
    return 0
