"""``vmnav demo``: teach routes, then repeat one to a goal on another path; report, plots, video.

See :mod:`tools.harness.demo` for the story, :mod:`tools.figures.demo_report` for what is
measured and :mod:`tools.figures.demo_plots` for the figures and the video,
:mod:`tools.harness.demo_log` for the robot's MCAP log.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import InputError
from tools.harness.progress import Progress
from tools.harness.repeat_args import add_repeat_arguments, repeat_setup_from_args
from tools.harness.scene_args import add_change_arguments
from tools.harness.sim_args import add_sim_arguments

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from sim.config import SimConfig
    from sim.renderer import RenderedFrame
    from sim.simulation import Simulation
    from tools.harness.demo import CycleSample

OnCycle = Callable[["Simulation", "RenderedFrame", "CycleSample"], None]


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav demo``."""
    demo = subparsers.add_parser(
        "demo",
        help="teach routes, then repeat one to a goal (simulator)",
        description="In one lock-step process: teach the routes into one visual memory (or "
        "reuse the one in OUT), place the robot 0.3 m and 10 degrees off the first route, "
        "localize, plan to a goal key image on another path and follow it there. Prints a "
        "summary and writes report.json, plots, a video and the robot's MCAP log (OUT/logs) "
        "into OUT.",
    )
    add_sim_arguments(demo)
    demo.add_argument("--out", type=Path, metavar="DIR",
                      help="output folder [default: out/demo; with --hil out/hil]")
    demo.add_argument("--hil", action="store_true",
                      help="hardware-in-the-loop: vmnav sim serve, vmnav robot and a ground "
                      "station as separate processes on TCP, HTTP and UDP; teach one route (the "
                      "world's first, or --routes NAME) by teleoperation, then repeat it from "
                      "the usual offset")
    demo.add_argument("--web", action="store_true",
                      help="with --hil: serve the web app on loopback while it runs (prints "
                      "its URL) and the robot's camera, to watch the demo in a browser")
    add_repeat_arguments(demo)
    add_change_arguments(demo)
    demo.add_argument("--no-video", action="store_true", help="do not write the MP4 video")
    demo.add_argument("--no-log", action="store_true",
                      help="do not write the robot's and the ground station's logs "
                      "(OUT/logs/robot-NNNN.mcap, ground-NNNN.mcap and a .tlog)")
    demo.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Teach (or reuse), repeat, write the outputs and print the summary."""
    from tools.figures.demo_plots import VideoWriter, write_plots
    from tools.figures.demo_report import build_report, dispatch_text, log_text, summary_text
    from tools.harness.demo import (
        START_OFFSET_M,
        check_goal,
        default_goal,
        repeat_in_sim,
        taught_memory,
    )
    from tools.harness.demo_log import DemoLog

    setup = repeat_setup_from_args(args)
    config, sim_config, change, routes = setup.config, setup.sim_config, setup.change, setup.routes
    if args.web and not args.hil:
        raise InputError("--web", "needs --hil (the lock-step demo has no ground station)")
    out: Path = args.out or Path("out/hil" if args.hil else "out/demo")
    if out.exists() and not out.is_dir():
        raise InputError(out, "is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    if args.hil:
        if routes is not None and len(routes) != 1:
            raise InputError("--routes", "--hil teaches one route")
        if not change.is_none or setup.start_offset_m != START_OFFSET_M:
            raise InputError("--hil", "repeats in the taught world from the usual offset: "
                             "--lighting, --moved, --removed, --doors and --start-offset are "
                             "for the lock-step demo")
        return run_hil_demo(out, config, sim_config, None if routes is None else routes[0],
                            args.web)
    started = time.perf_counter()
    taught = taught_memory(out, routes, config, sim_config, setup.camera)
    teach_s = time.perf_counter() - started
    goal = default_goal(taught) if args.goal is None else args.goal
    check_goal(taught.memory, goal)  # before the video and the log are opened
    video = None if args.no_video else VideoWriter(out / "demo.mp4", taught, sim_config, goal)
    robot_log = None if args.no_log else DemoLog(
        dataclasses.replace(config.log, output_dir=str(out / "logs"), replay_frames=True),
        config.camera.mount,
        {"source": "vmnav demo (simulator, lock-step)", "goal_key_image": str(goal),
         "routes": ",".join(routes) if routes else "all", "seed": str(sim_config.seed),
         "control_law": config.control.law},
        unix_offset_ns=time.time_ns())  # the repeat's simulation clock starts at 0 about now
    consumers = [c.add for c in (video, robot_log) if c is not None]
    repeat_started = time.perf_counter()
    try:
        with Progress(f"repeat to key image {goal}") as bar:
            if bar.shown:
                consumers.append(lambda sim, frame, sample: bar.update(detail=_status(sample)))
            repeat = repeat_in_sim(taught, goal, config, sim_config, change, out,
                                   _chain(consumers), robot_log,
                                   None if args.no_log else out / "logs",
                                   start_offset_m=setup.start_offset_m)
    finally:
        if video is not None:
            video.close()
        log_stats = None if robot_log is None else robot_log.close()
    report = build_report(repeat, taught, config.control, time.perf_counter() - repeat_started)
    report["teach_wall_time_s"] = round(teach_s, 2)
    report["memory_reused"] = taught.reused
    report["people"] = sim_config.people.count
    report["max_omega_deg"] = round(math.degrees(config.control.max_omega_rad_s), 3)
    report["control_law"] = config.control.law
    report["dispatch"] = {"transport": "MAVLink over loopback UDP",
                          "mission_upload_ms": (None if repeat.dispatch.upload_ms is None
                                                else round(repeat.dispatch.upload_ms, 1)),
                          "ground_saw_reached": repeat.dispatch.reached}
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    write_plots(out, repeat, taught)
    memory = taught.memory
    print(f"memory {out / 'memory'}: {len(memory.paths)} paths, {len(memory.keyframes)} key "
          f"images, {'reused' if taught.reused else f'taught in {teach_s:.1f} s'}")
    print(summary_text(report))
    print(f"wrote {out / 'report.json'}, plots{'' if video is None else ' and demo.mp4'}")
    print(dispatch_text(repeat.dispatch, goal))
    if robot_log is not None:
        print(log_text(log_stats))
    return 0 if report["reached_goal"] else 1


def run_hil_demo(out: Path, config: VmnavConfig, sim_config: SimConfig,
                 route: str | None, web: bool = False) -> int:
    """``vmnav demo --hil`` (``--web``: with the web app): run it, write ``report.json``,
    print the summary."""
    from tools.figures.demo_report import hil_summary_text
    from tools.harness.hil_demo import robot_config_text, run_hil

    robot_config = out / "robot.toml"
    robot_config.write_text(robot_config_text(config))
    report = run_hil(out, config, sim_config, robot_config, route, watch=(lambda url: print(
        f"vmnav demo: watch it at {url} (the web app, while the demo runs)", flush=True))
        if web else None)
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    print(hil_summary_text(report, out))
    return 0 if report["reached_goal"] else 1


def _status(sample: CycleSample) -> str:
    """One cycle as the progress line shows it: state, the key image headed for, time."""
    record = sample.record
    where = ""
    if record.target_number is not None:
        where = (f" to key image {record.target_key} ({record.target_number} of "
                 f"{len(record.targets)})")
    return f"{record.state.name.lower()}{where}, {record.t_ns / 1e9:.0f} s simulated"


def _chain(consumers: list[OnCycle]) -> OnCycle | None:
    """One ``on_cycle`` calling each of ``consumers`` in turn (None for none)."""
    if not consumers:
        return None
    if len(consumers) == 1:
        return consumers[0]

    def on_cycle(sim: Simulation, frame: RenderedFrame, sample: CycleSample) -> None:
        for consumer in consumers:
            consumer(sim, frame, sample)

    return on_cycle
