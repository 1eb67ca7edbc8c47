"""``vmnav bench ...``: benchmarks that print JSON (medians; one core)."""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

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
    vision.add_argument("--query-seed", type=int, default=0, help="seed of the query poses")
    vision.set_defaults(run=run_vision)
    follow = bench_sub.add_parser(
        "follow",
        help="route following: seeded demos without video, laws side by side",
        description="For each seed, teach the demo's routes (cached in OUT/seed<N>) and repeat "
        "the demo's mission once per control law; print per-seed rows and an aggregate per "
        "law (goal reached, final position error, lateral and heading errors on ground truth).",
    )
    add_sim_arguments(follow)
    follow.add_argument("--seeds", type=int, default=20, metavar="N",
                        help="number of seeds, from --seed on [default: 20]")
    follow.add_argument("--laws", nargs="+", default=["paper", "paper+ff"], metavar="LAW",
                        help="control laws to compare [default: paper paper+ff]")
    follow.add_argument("--max-omega-deg", type=float, default=None, metavar="DEG",
                        help="turn-rate bound, deg/s [default: the demo's]")
    follow.add_argument("--routes", nargs="+", metavar="NAME", help="routes [default: the demo's]")
    follow.add_argument("--goal", type=int, metavar="ID",
                        help="goal key image [default: the demo's]")
    follow.add_argument("--landmark-dropout", type=float, default=0.0, metavar="F",
                        help="fraction of landmarks removed before each repeat [default: 0]")
    follow.add_argument("--out", type=Path, default=Path("out/bench_follow"), metavar="DIR",
                        help="where the seeds' memories are cached [default: out/bench_follow]")
    follow.set_defaults(run=run_follow)
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
    log.set_defaults(run=run_log)
    link = bench_sub.add_parser(
        "link",
        help="MAVLink link: goal dispatch to MISSION_ACK, ground CPU following N vehicles",
        description="On loopback UDP, time one-goal mission uploads from the ground station "
        "to a simulated vehicle until the final MISSION_ACK, then measure the ground "
        "station's CPU time per wall second while it follows N simulated vehicles (other "
        "processes) streaming their default telemetry. The vehicles run a kinematic load "
        "generator, not the robot (tools/link_load.py). About 20 s at the defaults.",
    )
    link.add_argument("--vehicles", type=int, default=20, metavar="N",
                      help="simulated vehicles, system ids 1..N [default: 20]")
    link.add_argument("--window-s", type=float, default=10.0, metavar="S",
                      help="measured window with every vehicle following, s [default: 10]")
    link.add_argument("--dispatches", type=int, default=200, metavar="N",
                      help="timed goal uploads [default: 200]")
    link.add_argument("--vehicle-processes", type=int, default=2, metavar="N",
                      help="processes the vehicles are spread over [default: 2]")
    link.add_argument("--seed", type=int, default=0, help="seed of the dispatched goals")
    link.set_defaults(run=run_link)
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
    faults.set_defaults(run=run_faults)
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
    every.set_defaults(run=run_all, registry=bench_sub.choices)


def pin_to_one_core() -> list[int]:
    """Pin this process to one CPU, with one OpenCV thread and one BLAS thread; returns the
    CPU set.

    The BLAS limit matters: OpenBLAS starts one thread per CPU when numpy is imported,
    and its threads spin while they wait, so two of them sharing the pinned CPU made a
    localization among 300 key images (its prefilter's matrix product) take 330 ms
    instead of 8 ms.
    """
    import cv2
    from threadpoolctl import threadpool_limits

    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    cv2.setNumThreads(1)
    threadpool_limits(limits=1)
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


def run_vision(args: argparse.Namespace) -> int:
    """Print the vision benchmark's JSON."""
    import dataclasses

    from robot.config import load_config
    from shared.errors import InputError
    from tools.vision_bench import VisionBenchPlan, bench_vision

    sim_config, camera = sim_config_from_args(args)
    config = load_config(args.config)
    routes = tuple(args.routes) if args.routes else None
    plan = (VisionBenchPlan.quick(routes, args.query_seed) if args.quick
            else VisionBenchPlan(routes=routes, seed=args.query_seed))
    for name in ("state_queries", "localize_queries"):
        value = getattr(args, name)
        if value is not None:
            if value < 1:
                raise InputError(f"--{name.replace('_', '-')}", f"must be >= 1, got {value}")
            plan = dataclasses.replace(plan, **{name: value})
    cpus = pin_to_one_core()
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_vision(config, sim_config, camera, plan)
    print(json.dumps({"benchmark": "vision", "cpus": cpus, "load_average_at_start": load,
                      **result}, indent=2))
    return 0


def run_follow(args: argparse.Namespace) -> int:
    """Print the route-following benchmark's JSON."""
    from robot.config import CONTROL_LAWS, load_config
    from shared.errors import InputError
    from tools.demo import DEMO_MAX_OMEGA_DEG
    from tools.follow_bench import FollowBenchPlan, bench_follow

    if args.seeds < 1:
        raise InputError("--seeds", f"must be >= 1, got {args.seeds}")
    for law in args.laws:
        if law not in CONTROL_LAWS:
            raise InputError("--laws", f"unknown law {law!r} (known: {', '.join(CONTROL_LAWS)})")
    if not 0.0 <= args.landmark_dropout <= 1.0:
        raise InputError("--landmark-dropout", f"must be in [0, 1], got {args.landmark_dropout}")
    sim_config, camera = sim_config_from_args(args)
    config = load_config(args.config)
    plan = FollowBenchPlan(
        seeds=tuple(range(sim_config.seed, sim_config.seed + args.seeds)), laws=tuple(args.laws),
        max_omega_deg=DEMO_MAX_OMEGA_DEG if args.max_omega_deg is None else args.max_omega_deg,
        routes=tuple(args.routes) if args.routes else None, goal_id=args.goal,
        landmark_dropout=args.landmark_dropout)
    result = bench_follow(plan, args.out, config, sim_config, camera)
    print(json.dumps({"benchmark": "follow", **result}, indent=2))
    return 0


def run_log(args: argparse.Namespace) -> int:
    """Print the logging benchmark's JSON."""
    from shared.errors import InputError
    from shared.logs.bench import bench_log

    if not args.seconds > 0:
        raise InputError("--seconds", f"must be > 0, got {args.seconds}")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_log(seconds=args.seconds, out_dir=args.out)
    print(json.dumps({"benchmark": "log", "load_average_at_start": load, **result}, indent=2))
    return 0


def run_link(args: argparse.Namespace) -> int:
    """Print the MAVLink link benchmark's JSON."""
    from shared.errors import InputError
    from tools.link_bench import LinkBenchPlan, bench_link

    if not 1 <= args.vehicles <= 254:
        raise InputError("--vehicles", f"must be in 1..254, got {args.vehicles}")
    if not args.window_s > 0:
        raise InputError("--window-s", f"must be > 0, got {args.window_s}")
    for name in ("dispatches", "vehicle_processes"):
        value = getattr(args, name)
        if value < 1:
            raise InputError(f"--{name.replace('_', '-')}", f"must be >= 1, got {value}")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_link(LinkBenchPlan(
        vehicles=args.vehicles, window_s=args.window_s, dispatches=args.dispatches,
        vehicle_processes=args.vehicle_processes, seed=args.seed))
    print(json.dumps({"benchmark": "link", "load_average_at_start": load, **result}, indent=2))
    return 0


def run_faults(args: argparse.Namespace) -> int:
    """Print the fault benchmark's JSON (exit 0 whatever the cases did: the JSON says)."""
    import sys
    import tempfile

    from shared.errors import InputError
    from tools.fault_bench import CASES, bench_faults

    if args.repeat < 1:
        raise InputError("--repeat", f"must be >= 1, got {args.repeat}")
    names = list(CASES) if args.cases is None else picked("--cases", args.cases, list(CASES),
                                                          "case")

    def progress(line: str) -> None:
        print(f"vmnav bench faults: {line}", file=sys.stderr, flush=True)

    with tempfile.TemporaryDirectory(prefix="vmnav-faults-") as scratch:
        folder = args.out if args.out is not None else Path(scratch)
        result = bench_faults(names, args.repeat, folder, progress,
                              keep_passed=args.out is not None)
    print(json.dumps(result, indent=2))
    return 0


def picked(option: str, text: str, known: list[str], kind: str) -> list[str]:
    """The names of the comma-separated ``text``, each one of ``known``.

    Raises:
        InputError: a name is not known, or there is none (names ``option``).
    """
    from shared.errors import InputError

    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in known]
    if unknown or not names:
        what = f"unknown {kind} {', '.join(unknown)}" if unknown else f"no {kind}"
        raise InputError(option, f"{what} (known: {', '.join(known)})")
    return names


def run_all(args: argparse.Namespace) -> int:
    """Run every benchmark; print the document and the table; write both into ``--out``."""
    import shlex
    import sys

    from shared.atomic_file import write_text_atomic
    from shared.errors import InputError
    from tools.bench_all import document, exit_code, markdown_table
    from tools.bench_all import run_all as run_benchmarks

    known = [name for name in args.registry if name != "all"]
    names = known if args.only is None else picked("--only", args.only, known, "benchmark")
    extra: dict[str, list[str]] = {}
    for item in args.bench_args:
        name, sep, rest = item.partition("=")
        if not sep or name not in known:
            raise InputError("--bench-args", f"{item!r} is not NAME=ARGS with NAME one of "
                             f"{', '.join(known)}")
        extra.setdefault(name, []).extend(shlex.split(rest))
    if not args.timeout_s > 0:
        raise InputError("--timeout-s", f"must be > 0, got {args.timeout_s}")
    runs = run_benchmarks(names, args.quick, args.out, extra, args.timeout_s,
                          lambda line: print(f"vmnav bench all: {line}", file=sys.stderr))
    text, table = json.dumps(document(runs), indent=2), markdown_table(runs)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out / "bench_all.json", text + "\n")
    write_text_atomic(args.out / "bench_all.md", table + "\n")
    print(text)
    print()
    print(table)
    return exit_code(runs)
