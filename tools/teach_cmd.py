"""``vmnav teach --sim``: teach a route of a simulated world into a visual memory.

1. :func:`tools.harness.teach.teach_in_sim` drives the route in the simulator in
   lock-step and selects key images from the frames and the wheel odometry;
2. the key images become a new path of the memory, whose ends are localized
   against the other paths to make junctions
   (:func:`robot.memory.junctions.junction_attempts`);
3. :func:`shared.memory.write_memory` stores it (adding to what ``DIR`` holds).

With ``--log LOGDIR`` the drive's frames and odometry are also recorded, as a robot's
teach run is, in ``LOGDIR/teach-<route>-NNNN.mcap`` (:meth:`robot.field_log.FieldLog.teach_frame`),
which ``vmnav memory build`` turns into the same path.
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import InputError
from tools.harness.sim_args import add_sim_arguments, sim_config_from_args

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.memory.junctions import JunctionAttempt
    from shared.logs.writer import LogStats
    from shared.memory import VisualMemory, VisualPath
    from tools.harness.teach import TaughtRoute


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav teach``."""
    teach = subparsers.add_parser(
        "teach",
        help="teach a route into a visual memory (simulator)",
        description="Drive the simulated robot along a named route of the world with a "
        "scripted human-like driver, select key images from its frames and odometry, and add "
        "the visual path to the memory in DIR (created if needed), joined to the paths already "
        "there where its ends are localized.",
    )
    teach.add_argument(
        "--sim", action="store_true", help="teach in the simulator (the only mode for now)"
    )
    add_sim_arguments(teach)
    teach.add_argument("--route", required=True, metavar="NAME", help="a route of the world")
    teach.add_argument(
        "--memory", required=True, type=Path, metavar="DIR", help="the visual memory's folder"
    )
    teach.add_argument(
        "--log",
        type=Path,
        metavar="LOGDIR",
        help="also record the drive's frames and odometry in LOGDIR/teach-ROUTE-NNNN.mcap "
        "(for 'vmnav memory build')",
    )
    teach.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Teach the route, store the path and print a summary."""
    from robot.config import load_config
    from robot.field_log import FieldLog
    from robot.memory.junctions import join_path
    from robot.vision.front_end import check_front_end, front_end_label
    from shared.memory import open_or_create, write_memory
    from sim.world import load_world
    from tools.harness.teach import find_route, teach_in_sim

    if not args.sim:
        raise InputError("vmnav teach", "only --sim is available: teach in the simulator")
    sim_config, camera = sim_config_from_args(args)
    config = load_config(args.config)
    world = load_world(sim_config.world)
    route = find_route(world, args.route)
    memory = open_or_create(args.memory, camera)
    check_front_end(memory, config.features)  # before driving, not after
    started = time.perf_counter()
    teach_log = None if args.log is None else FieldLog(
        dataclasses.replace(config.log, output_dir=str(args.log)), f"teach-{route.name}",
        config.camera.mount,
        {"source": "vmnav teach --sim (lock-step)", "world": world.name, "route": route.name,
         "seed": str(sim_config.seed)},
        unix_offset_ns=time.time_ns())  # the simulation clock's zero: the run's start
    try:
        taught = teach_in_sim(world, route, config, sim_config, camera,
                              None if teach_log is None else teach_log.teach_frame)
    finally:
        log_stats = None if teach_log is None else teach_log.close()
    path = memory.add_path(route.name, [k.record for k in taught.key_images],
                           front_end_label(config.features, memory.camera))
    attempts = join_path(memory, path, config.camera.mount, config.features, config.localize,
                  config.teach)
    write_memory(args.memory, memory)
    wall_s = time.perf_counter() - started
    print(summary_text(taught, path, memory, attempts, config, args.memory, wall_s))
    if log_stats is not None:
        print(log_text(log_stats))
    return 0


def log_text(stats: LogStats) -> str:
    """The line ``vmnav teach`` prints about its log: the file and any messages lost."""
    files = ", ".join(str(f) for f in stats.files) or "no file"
    lost = stats.dropped + stats.lost
    problem = (f"; {lost} messages dropped or lost ({stats.last_error or 'queue full'})"
               if lost else "")
    return f"log {files}: {stats.written} messages{problem}"


def summary_text(
    taught: TaughtRoute,
    path: VisualPath,
    memory: VisualMemory,
    attempts: list[JunctionAttempt],
    config: VmnavConfig,
    directory: Path,
    wall_s: float,
) -> str:
    """What ``vmnav teach`` prints: the new path, its junctions, the memory."""
    import numpy as np

    from robot.memory.junctions import junction_lines

    distances = np.array([memory.keyframes[i].distance_m for i in path.keyframe_ids])
    length_m = float(distances[-1])
    steps = np.diff(distances)
    n = len(path.keyframe_ids)
    lines = [
        f"taught route {taught.route.name!r} as path {path.id}: {n} key images "
        f"(ids {path.keyframe_ids[0]}-{path.keyframe_ids[-1]}) over {length_m:.2f} m of "
        f"odometry, {n / length_m:.2f} key images per metre"
        if length_m > 0
        else f"taught route {taught.route.name!r} as path {path.id}: {n} key image(s), no motion",
    ]
    if steps.size:
        lines.append(
            f"  spacing {float(np.median(steps)):.2f} m median, {float(steps.min()):.2f}-"
            f"{float(steps.max()):.2f} m; {taught.frames} frames, {taught.sim_time_s:.1f} s "
            f"simulated in {wall_s:.1f} s"
        )
    m = config.teach.min_tracked_points
    weak = [k for k in taught.key_images[1:-1] if k.shared_points < m]
    if weak:
        lines.append(f"  {len(weak)} key images forced with fewer than M = {m} tracked points")
    lines.extend(junction_lines(attempts, memory, directory))
    return "\n".join(lines)
