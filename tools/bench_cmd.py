"""``vmnav bench ...``: benchmarks that print JSON (medians; one core).

This module declares the command line; each benchmark's module in :mod:`tools.bench` has a
``run(args)``, imported only when it runs (OpenCV, pymunk): ``vmnav --help`` stays fast.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from pathlib import Path

from tools import bench_foxglove_cmd, bench_safety_cmd, bench_sweep_cmd, bench_web_cmd
from tools.harness.arg_types import POSITIVE_COUNT, SEED
from tools.harness.sim_args import add_sim_arguments


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav bench`` and its benchmarks."""
    bench = subparsers.add_parser("bench", help="benchmarks printing JSON")
    bench_sub = bench.add_subparsers(dest="bench_command", metavar="BENCHMARK", required=True)
    sim = bench_sub.add_parser(
        "sim", help="simulator: physics + rendering frames/s, camera-model accuracy",
        description="Drive the simulated robot along a route and time physics + rendering per "
        "frame on one core; check the camera model's round trip and agreement with cv2.omnidir.",
    )
    add_sim_arguments(sim)
    sim.add_argument("--frames", type=POSITIVE_COUNT, default=300, help="frames [default: 300]")
    sim.set_defaults(run=runner("sim"))
    vision = bench_sub.add_parser(
        "vision",
        help="vision: frame time, y/theta accuracy, localization, on taught sim routes",
        description="Teach the world's routes in the simulator, then measure on rendered views "
        "with ground truth: the per-frame pipeline's time (Harris + ZNCC + lifting + state + "
        "image errors, one core), the y and theta errors between two key images, and "
        "localization (top-1 rate; time for memories of about 300 and 3000 key images against "
        "the paper's exhaustive rule). About a minute on lab; --quick is a small run.",
    )
    add_sim_arguments(vision)
    vision.add_argument("--routes", nargs="+", metavar="NAME", help="routes [default: all]")
    vision.add_argument("--quick", action="store_true",
                        help="few queries (12 state, 10 localization): a smoke run")
    vision.add_argument("--state-queries", type=int, metavar="N",
                        help="views for y/theta and frame time [default: 300]")
    vision.add_argument("--localize-queries", type=int, metavar="N",
                        help="views for the localization rate [default: 200]")
    vision.add_argument("--query-seed", type=SEED, default=0, help="seed of the query poses")
    vision.set_defaults(run=runner("vision"))
    bench_sweep_cmd.add_parsers(bench_sub, runner("follow"), runner("sweep"))
    log = bench_sub.add_parser(
        "log",
        help="field logging: CPU cost of 15 frames/s of 800x600 JPEG plus telemetry",
        description="Run a loop producing 800x600 grey frames at 15 frames/s and 50 Hz "
        "telemetry, alternating phases with MCAP logging off and on; print the process CPU "
        "time per wall second with logging minus without (log_overhead_core_fraction).",
    )
    log.add_argument("--seconds", type=float, default=8.0,
                     help="total wall time, four phases (off, on, off, on) [default: 8]")
    log.add_argument("--out", type=Path, metavar="DIR",
                     help="keep the logs written in DIR [default: a temporary folder]")
    log.set_defaults(run=runner("log"))
    link = bench_sub.add_parser(
        "link",
        help="MAVLink link: goal dispatch to MISSION_ACK, ground CPU following N vehicles",
        description="On loopback UDP, time one-goal mission uploads from the ground station "
        "to a simulated vehicle until the final MISSION_ACK, then measure the ground "
        "station's CPU time per wall second while it follows N simulated vehicles (other "
        "processes) streaming their default telemetry. The vehicles run a kinematic load "
        "generator, not the robot (tools/bench/link_load.py). About 20 s at the defaults.",
    )
    link.add_argument("--vehicles", type=int, default=20, metavar="N",
                      help="simulated vehicles, system ids 1..N [default: 20]")
    link.add_argument("--window-s", type=float, default=10.0, metavar="S",
                      help="measured window with every vehicle following, s [default: 10]")
    link.add_argument("--dispatches", type=int, default=200, metavar="N",
                      help="timed goal uploads [default: 200]")
    link.add_argument("--vehicle-processes", type=POSITIVE_COUNT, default=2, metavar="N",
                      help="processes the vehicles are spread over [default: 2]")
    link.add_argument("--seed", type=SEED, default=0, help="seed of the dispatched goals")
    link.set_defaults(run=runner("link"))
    faults = bench_sub.add_parser(
        "faults",
        help="issue 8's fault cases on the hardware-in-the-loop rig, each repeated",
        description="Teach a 2.5 m route in lock-step, then run every fault case of issue 8 "
        "(ARIA link cut, camera stall, ground station silent, SIGKILL, garbage at every "
        "boundary) on the hardware-in-the-loop rig: the simulator's ARIA server and camera in "
        "this process, vmnav robot as a subprocess, a ground station over UDP. Each case runs "
        "--repeat times in a row, each time on a fresh rig; print JSON {case: {passed, runs, "
        "failures, wall_s_max}}. One repetition of every case takes about 2 min.",
    )
    faults.add_argument("--repeat", type=int, default=10, metavar="N",
                        help="runs of each case [default: 10, issue 8's 'passes 10 times in "
                             "a row']")
    faults.add_argument("--cases", metavar="NAMES",
                        help="comma-separated cases to run [default: all]")
    faults.add_argument("--out", type=Path, metavar="DIR",
                        help="keep every run's folder (memory, parameters, logs, the robot's "
                             "output) in DIR [default: a temporary folder, removed at the end]")
    faults.set_defaults(run=runner("faults"))
    fuzz = bench_sub.add_parser(
        "fuzz",
        help="issue 15: seeded fuzzing of every decoder and loader, crashes and hangs counted",
        description="Feed seeded, structure-aware mutated inputs to every decoder and loader "
        "(ARIA robot and host ends, the MAVLink vehicle unsigned and signed, the memory "
        "loader, MCAP info/read/recover, the photo goal), each target in a worker process "
        "with a time limit per input and a memory limit; print JSON: per target inputs, "
        "crashes (any exception but the project's input errors), hangs, the slowest "
        "input, and the first crashing inputs with their errors (docs/fuzzing.md).",
    )
    fuzz.add_argument("--inputs", type=int, default=100_000, metavar="N",
                      help="inputs per target [default: 100000]")
    fuzz.add_argument("--targets", metavar="NAMES",
                      help="comma-separated targets to fuzz [default: all]")
    fuzz.add_argument("--seed", type=SEED, default=0, help="seed of the inputs [default: 0]")
    fuzz.add_argument("--time-limit-s", type=float, default=10.0, metavar="S",
                      help="an input running longer is a hang, s [default: 10]")
    fuzz.add_argument("--memory-limit-mb", type=POSITIVE_COUNT, default=1024, metavar="MB",
                      help="address space a worker may add to what it holds after setup, "
                           "MB; beyond it an input fails as a crash [default: 1024]")
    fuzz.set_defaults(run=runner("fuzz"))
    hostile = bench_sub.add_parser(
        "hostile",
        help="issue 15: attacks on the real parts (bad messages, signing, flood, a stalled "
             "loop, image and file bombs, the simulator), about 3 min",
        description="Run each attack of issue 15 against the real parts, one after the other "
        "(processes, sockets and files; our code on both ends): hostile MAVLink messages, "
        "wrong keys and replays, a 20 s flood and 65,025 FTP peers, a control loop stalled "
        "while driving, image bombs, hostile memories and logs, hostile ARIA packets and "
        "HTTP requests against the simulator. Print JSON: each part's figures, the targets "
        "and whether each is met (tools/bench/hostile.py).",
    )
    hostile.add_argument("--parts", metavar="NAMES",
                         help="comma-separated parts to run [default: all: messages, signing, "
                              "traffic, stall, images, files, sim]")
    hostile.add_argument("--seed", type=SEED, default=0, help="seed of every part [default: 0]")
    hostile.set_defaults(run=runner("hostile"))
    real = bench_sub.add_parser(
        "real", help="issue 16: real images: catadioptric calibration, equidistant import, "
        "the fisheye pair's relative pose per front end",
        description="Calibrate OpenCV's catadioptric test set (../shared/realdata) against "
        "its reference focal lengths and xi; fit the unified model to the vendored fisheye "
        "pair's equidistant calibrations (residual); match the pair and fit its relative "
        "pose with the paper's front end and the default, against the reference from the "
        "rig's T_BS, timing each pair on one core. About 20 s.")
    real.add_argument("--repeats", type=int, default=10, metavar="N",
                      help="timed runs of each front end on the pair [default: 10]")
    real.set_defaults(run=runner("real"))
    bench_safety_cmd.add_parser(bench_sub, runner("safety"))
    bench_foxglove_cmd.add_parser(bench_sub, runner("foxglove"))
    bench_web_cmd.add_parser(bench_sub, runner("web"))
    chance = bench_sub.add_parser("chance", help="issue 16: pairs of unrelated real images "
                                  "through localization's acceptance test (target: none pass)")
    chance.add_argument("--realdata", type=Path, metavar="DIR", help="real image sets' folder")
    chance.add_argument("--config", metavar="FILE", help="vmnav TOML config")
    chance.set_defaults(run=runner("chance"))
    # Registered last: ``all`` runs what ``bench_sub.choices`` holds when it runs.
    every = bench_sub.add_parser(
        "all",
        help="every benchmark above, each in its own process: one JSON document and a "
        "markdown table of figures beside their targets",
        description="Run every benchmark (sim, vision, follow, log, link, ...) one after the "
        "other as a subprocess; print one JSON document (benchmark -> figures, targets, its "
        "own JSON or its error) and a markdown table (benchmark, figure, value, target, "
        "pass/fail), also written to OUT/bench_all.json and OUT/bench_all.md. Exit code 0: "
        "all ran and met their targets; 1: a benchmark failed; 3: a target was missed. "
        "--quick takes about 3 min; the full run about 42 min, 40 of them follow's 20 "
        "seeds (22 min once their memories are cached in OUT/follow).",
    )
    every.add_argument("--quick", action="store_true",
                       help="reduced sizes (fewer frames, seeds, dispatches...): a smoke run")
    every.add_argument("--only", metavar="NAMES",
                       help="comma-separated benchmarks to run [default: all]")
    every.add_argument("--bench-args", action="append", default=[], metavar="NAME=ARGS",
                       help="extra arguments for one benchmark, e.g. 'follow=--world campus' "
                       "(repeatable; they come last, so they override)")
    every.add_argument("--out", type=Path, default=Path("out/bench_all"), metavar="DIR",
                       help="results and follow's memory cache [default: out/bench_all]")
    every.add_argument("--timeout-s", type=float, default=7200.0, metavar="S",
                       help="time limit of each benchmark, s [default: 7200]")
    every.set_defaults(run=runner("run_all"), registry=bench_sub.choices)


def runner(module: str) -> Callable[[argparse.Namespace], int]:
    """The ``run`` of :mod:`tools.bench`'s ``module``, imported when the benchmark runs."""

    def run(args: argparse.Namespace) -> int:
        return int(importlib.import_module(f"tools.bench.{module}").run(args))

    return run
