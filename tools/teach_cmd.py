"""``vmnav teach --sim``: teach a route of a simulated world into a visual memory.

The loop couples the simulator and the robot's code, so it lives here (robot/
never imports sim/, sim/ never imports robot/):

1. :func:`sim.teach_recording.record_drive` drives the simulated robot along the
   route with the scripted human-like :class:`sim.teach_driver.TeachDriver`, in
   lock-step, one rendered frame per camera period;
2. each frame's image and the body's wheel odometry (not the truth) go to
   :class:`robot.teach.KeyImageSelector`;
3. the key images become a new path of the memory, whose ends are localized
   against the other paths to make junctions
   (:func:`robot.memory.junctions.junction_attempts`);
4. :func:`shared.memory.write_memory` stores it (adding to what ``DIR`` holds).

With ``--log LOGDIR`` the drive's frames and odometry are also recorded, as a robot's
teach run is, in ``LOGDIR/teach-<route>-NNNN.mcap`` (:meth:`robot.field_log.FieldLog.teach_frame`),
which ``vmnav memory build`` turns into the same path.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import InputError
from tools.sim_args import add_sim_arguments, sim_config_from_args

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.memory.junctions import JunctionAttempt
    from robot.teach import OdomPose, SelectedKeyImage
    from robot.vision.features import GreyImage
    from shared.camera_model import CameraModel
    from shared.logs.writer import LogStats
    from shared.memory import VisualMemory, VisualPath
    from sim.config import SimConfig
    from sim.world import Route, World

#: Mixed with the simulation seed for the teach driver's random wander.
DRIVER_STREAM = 0x54454143
#: A drive may take this many times its length at the minimum cruise speed before it is abandoned.
_DURATION_MARGIN = 3.0
#: ... plus this, s (start and stop).
_DURATION_EXTRA_S = 30.0


@dataclass(frozen=True, eq=False)
class TaughtRoute:
    """A route driven in the simulator and cut into key images.

    Attributes:
        route: the route driven.
        key_images: the selected key images in driving order.
        true_poses: the true robot pose (x_m, y_m, yaw_rad) of each key image (evaluation only).
        frames: frames recorded.
        sim_time_s: simulated duration of the drive, s.
    """

    route: Route
    key_images: tuple[SelectedKeyImage, ...]
    true_poses: tuple[tuple[float, float, float], ...]
    frames: int
    sim_time_s: float


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
    from shared.memory import write_memory
    from sim.world import load_world

    if not args.sim:
        raise InputError("vmnav teach", "only --sim is available: teach in the simulator")
    sim_config, camera = sim_config_from_args(args)
    config = load_config(args.config)
    world = load_world(sim_config.world)
    route = find_route(world, args.route)
    memory = open_memory(args.memory, camera)
    started = time.perf_counter()
    teach_log = None if args.log is None else FieldLog(
        dataclasses.replace(config.log, output_dir=str(args.log)), f"teach-{route.name}",
        config.camera.mount,
        {"source": "vmnav teach --sim (lock-step)", "world": world.name, "route": route.name,
         "seed": str(sim_config.seed)})
    try:
        taught = teach_in_sim(world, route, config, sim_config, camera,
                              None if teach_log is None else teach_log.teach_frame)
    finally:
        log_stats = None if teach_log is None else teach_log.close()
    path = memory.add_path(route.name, [k.record for k in taught.key_images])
    attempts = join_path(memory, path, config.features, config.localize, config.teach)
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


def find_route(world: World, name: str) -> Route:
    """The route ``name`` of ``world``.

    Raises:
        InputError: no such route (the message lists the world's routes).
    """
    for route in world.routes:
        if route.name == name:
            return route
    known = ", ".join(r.name for r in world.routes) or "none"
    raise InputError("--route", f"unknown route {name!r} in world {world.name!r} (known: {known})")


def open_memory(directory: Path, camera: CameraModel) -> VisualMemory:
    """The memory in ``directory`` to add to, or a new one; checked before any driving.

    Raises:
        InputError: ``directory`` is not a writable folder, or holds a memory taught
            with another camera.
        MemoryFormatError: the memory in ``directory`` does not load, or ``directory`` holds
            files but no manifest (a new memory would be written over them).
    """
    from shared.calibration import camera_to_dict
    from shared.memory import VisualMemory, read_memory
    from shared.memory.store import MANIFEST_NAME, check_no_orphans

    if directory.exists() and not directory.is_dir():
        raise InputError(directory, "is not a folder")
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(directory, f"cannot create the memory folder: {e.strerror}") from None
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(directory, "the memory folder is not writable")
    check_no_orphans(directory)
    if not (directory / MANIFEST_NAME).exists():
        return VisualMemory(camera)
    memory = read_memory(directory)
    if camera_to_dict(memory.camera) != camera_to_dict(camera):
        raise InputError(
            directory, "the memory was taught with another camera than the simulated one"
        )
    return memory


def teach_in_sim(
    world: World,
    route: Route,
    config: VmnavConfig,
    sim_config: SimConfig,
    camera: CameraModel,
    on_frame: Callable[[int, GreyImage, OdomPose], None] | None = None,
) -> TaughtRoute:
    """Drive ``route`` in lock-step and select its key images from frames and odometry.

    Args:
        world: the world of the route.
        route: the route to drive, from its start pose.
        config: teach and feature parameters.
        sim_config: the simulation's config (the teach driver's too; its seed seeds the
            driver).
        camera: the simulated camera.
        on_frame: called with each frame's (t_ns, image, odometry pose), e.g.
            :meth:`robot.field_log.FieldLog.teach_frame`.

    Raises:
        InputError: the drive did not reach the route's end in time.
    """
    import numpy as np

    from robot.teach import KeyImageSelector
    from sim.renderer import FisheyeRenderer
    from sim.simulation import Simulation
    from sim.teach_driver import TeachDriver
    from sim.teach_recording import record_drive

    sim = Simulation(world, sim_config)
    sim.place_robot(route.start_pose())
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    driver_config = sim_config.teach_driver
    driver = TeachDriver(
        route.waypoints, driver_config, np.random.default_rng([sim_config.seed, DRIVER_STREAM])
    )
    slowest_m_s = driver_config.speed_m_s * (1.0 - driver_config.speed_variation)
    max_duration_s = _DURATION_MARGIN * driver.length_m / slowest_m_s + _DURATION_EXTRA_S
    selector = KeyImageSelector(camera, config.features, config.teach)
    key_images: list[SelectedKeyImage] = []
    true_poses: list[tuple[float, float, float]] = []
    frames = 0
    for frame in record_drive(sim, renderer, driver, round(max_duration_s * 1e9)):
        true_poses.append(frame.pose_w)
        if on_frame is not None:
            on_frame(frame.t_ns, frame.image, frame.odom_pose)
        key_images.extend(selector.push(frame.t_ns, frame.image, frame.odom_pose))
        frames += 1
    key_images.extend(selector.finish())
    if not driver.done:
        raise InputError(
            f"route {route.name!r}",
            f"the teach drive did not reach the end in {max_duration_s:.0f} s of simulated time",
        )
    return TaughtRoute(
        route=route,
        key_images=tuple(key_images),
        true_poses=tuple(true_poses[k.frame_index] for k in key_images),
        frames=frames,
        sim_time_s=sim.now_ns / 1e9,
    )


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


def junction_lines(
    attempts: Sequence[JunctionAttempt], memory: VisualMemory, directory: Path
) -> list[str]:
    """The end of a teach summary: the junctions made and tried, then the memory."""
    made = [a for a in attempts if a.accepted]
    lines = [f"  junctions made: {len(made)}"]
    for a in attempts:
        lines.append(
            f"    end key image {a.end_id}: best key image {a.best_id} with {a.matches} "
            f"matches: {a.outcome.value}"
        )
    lines.append(
        f"memory {directory}: {len(memory.paths)} paths, {len(memory.keyframes)} key images, "
        f"{len(memory.junctions)} junctions"
    )
    return lines
