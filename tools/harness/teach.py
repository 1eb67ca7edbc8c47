"""Teach routes of a simulated world in lock-step, keeping the true poses.

The loop couples the simulator and the robot's code, so it lives in the harness (robot/
never imports sim/, sim/ never imports robot/):

1. :func:`teach_in_sim` drives one route: :func:`sim.teach_recording.record_drive`
   moves the simulated robot along it with the scripted human-like
   :class:`sim.teach_driver.TeachDriver`, in lock-step, one rendered frame per camera
   period; each frame's image and the body's wheel odometry (not the truth) go to
   :class:`robot.teach.KeyImageSelector`. ``vmnav teach --sim`` adds the key images to a
   memory as a new path.
2. :func:`teach_memory` teaches several routes into one memory, one path each, and keeps
   the true pose of every key image (:class:`TaughtMemory`), for everything that
   measures against the truth: ``vmnav demo``, the benchmarks, the fault cases' rig. It
   can join the paths as ``vmnav teach`` does, and store the memory in a folder with a
   record of what was taught, to be reused when asked again for the same. The routes'
   drives are independent (each its own simulation, seeded alike), so they run in
   parallel, one process per CPU this process may use; joining follows in teaching
   order, and the memory is the same as taught one route after another.
"""

from __future__ import annotations

import json
import logging
import multiprocessing
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shared.errors import InputError
from shared.pose import Pose2
from tools.harness.stop_signals import terminate_children

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.teach import SelectedKeyImage
    from robot.vision.features import GreyImage
    from shared.camera_model import CameraModel
    from shared.memory import VisualMemory
    from sim.config import SimConfig
    from sim.world import Route, World

_log = logging.getLogger(__name__)

#: The truth of a memory stored by :func:`teach_memory`, beside its ``memory`` folder.
TRUTH_NAME = "teach.json"
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
        true_poses: the true robot pose of each key image, world frame (evaluation only).
        frames: frames recorded.
        sim_time_s: simulated duration of the drive, s.
    """

    route: Route
    key_images: tuple[SelectedKeyImage, ...]
    true_poses: tuple[Pose2, ...]
    frames: int
    sim_time_s: float


@dataclass(frozen=True, eq=False)
class TaughtMemory:
    """Routes taught into one memory, with the truth that the memory does not keep.

    Attributes:
        memory: the visual memory, one path per route.
        true_poses: true robot pose of every key image by id, world frame (evaluation only).
        path_ids: the path id of each route, in teaching order.
        routes: what each route's drive gave, in teaching order; empty when reused.
        reused: the memory was read from a folder taught before instead of taught.
    """

    memory: VisualMemory
    true_poses: dict[int, Pose2]
    path_ids: tuple[int, ...]
    routes: tuple[TaughtRoute, ...]
    reused: bool


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


def teach_in_sim(
    world: World,
    route: Route,
    config: VmnavConfig,
    sim_config: SimConfig,
    camera: CameraModel,
    on_frame: Callable[[int, GreyImage, Pose2], None] | None = None,
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
    true_poses: list[Pose2] = []
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


def teach_memory(
    world: World,
    route_names: Sequence[str] | None,
    config: VmnavConfig,
    sim_config: SimConfig,
    camera: CameraModel,
    *,
    join: bool,
    folder: Path | None = None,
    processes: int | None = None,
) -> TaughtMemory:
    """Teach routes of ``world`` (:func:`teach_in_sim`, each from its start pose) into one
    memory, one path per route, keeping the true pose of every key image.

    Args:
        world: the world of the routes (``sim_config.world`` loaded).
        route_names: route names in teaching order; None: all the world's routes in the
            order its file lists them.
        config: teach, driver, feature and localization parameters.
        sim_config: the simulation's config while teaching (world name, seed, people).
        camera: the simulated camera.
        join: join each new path to the ones taught before it where its ends are
            localized (:func:`robot.memory.junctions.join_path`, as ``vmnav teach``).
        folder: None: keep the memory in memory only. Else store it in ``folder/memory``
            and the truth in ``folder/teach.json`` under a key (world, seed, route
            names, camera, and ``"joined": false`` when not joined). A memory already
            there with the same key is read instead of taught; a memory there taught
            otherwise (or without ``teach.json``) is an error, never overwritten; a
            folder :func:`shared.memory.open_or_create` refuses is refused before driving.
        processes: at most this many processes drive the routes (None: one per CPU this
            process may use; 1: in this process, e.g. a sweep's worker).

    Raises:
        InputError: an unknown route, a world without routes, a drive that does not reach
            its end, or ``folder`` holding a memory taught otherwise.
        MemoryFormatError: ``folder/memory`` holds files but no manifest, or a memory
            that does not load.
    """
    from robot.memory.junctions import join_path
    from robot.vision.front_end import front_end_label
    from shared.memory import VisualMemory, open_or_create, write_memory

    routes = (list(world.routes) if route_names is None
              else [find_route(world, name) for name in route_names])
    if not routes:
        raise InputError(f"world {world.name!r}", "has no routes to teach")
    memory = VisualMemory(camera)
    if folder is not None:
        key = _truth_key(sim_config, [r.name for r in routes], camera, join)
        stored = _stored_truth(folder, key)
        memory = open_or_create(folder / "memory", camera)
        if stored is not None:
            return taught_from_truth(memory, stored)
    true_poses: dict[int, Pose2] = {}
    path_ids: list[int] = []
    taught_routes: list[TaughtRoute] = []
    for taught in _drive_routes(world, routes, config, sim_config, camera, processes):
        route = taught.route
        path = memory.add_path(route.name, [k.record for k in taught.key_images],
                               front_end_label(config.features, memory.camera))
        if join:
            join_path(memory, path, config.camera.mount, config.features, config.localize,
                      config.teach)
        true_poses.update(zip(path.keyframe_ids, taught.true_poses, strict=True))
        path_ids.append(path.id)
        taught_routes.append(taught)
    if folder is not None:
        write_memory(folder / "memory", memory)
        (folder / TRUTH_NAME).write_text(json.dumps(
            {"key": key, "path_ids": path_ids,
             "true_poses": {str(k): v for k, v in true_poses.items()}}))
    return TaughtMemory(memory=memory, true_poses=true_poses, path_ids=tuple(path_ids),
                        routes=tuple(taught_routes), reused=False)


def _drive_routes(world: World, routes: list[Route], config: VmnavConfig,
                  sim_config: SimConfig, camera: CameraModel,
                  processes: int | None) -> list[TaughtRoute]:
    """:func:`teach_in_sim` for each of ``routes``, in their order: in this process when
    one route or one CPU, else in a pool of processes (spawned: this process may hold
    threads), one per CPU this process may use (at most ``processes``), at most one per
    route, the longest routes first so that the pool ends together; each renders on one
    thread.

    Each drive's end is logged as it comes (:func:`_announce`).

    Raises:
        InputError: a drive did not reach its route's end (the first to end so).
    """
    workers = min(len(routes), len(os.sched_getaffinity(0)), processes or len(routes))
    started = time.monotonic()
    if workers <= 1:
        return [_announce(teach_in_sim(world, route, config, sim_config, camera), started)
                for route in routes]
    from tools.threads import compute_threads

    pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=compute_threads, initargs=(1,))
    try:
        longest_first = sorted(routes, key=lambda route: -route.length_m)
        drives = {pool.submit(teach_in_sim, world, route, config, sim_config, camera): route.name
                  for route in longest_first}
        taught = {drives[drive]: _announce(drive.result(), started)
                  for drive in as_completed(drives)}
        return [taught[route.name] for route in routes]
    except BaseException:
        # Ctrl-C, SIGTERM (``tools.cli`` raises SystemExit) or a drive that failed: the
        # other drives would run on for minutes, and outlive this process if it is then
        # killed. The pool's are this process's only children while it teaches.
        terminate_children()
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _announce(taught: TaughtRoute, started: float) -> TaughtRoute:
    """Log that a route's drive ended (progress of a teach that takes minutes)."""
    _log.info("teach: route %s driven: %d key images, %.1f m in %.1f s simulated (%.0f s "
              "since the teach started)", taught.route.name, len(taught.key_images),
              taught.route.length_m, taught.sim_time_s, time.monotonic() - started)
    return taught


def taught_from_truth(memory: VisualMemory, truth: dict[str, Any]) -> TaughtMemory:
    """A memory taught before and its ``teach.json`` (:func:`teach_memory`), as taught."""
    return TaughtMemory(memory=memory,
                        true_poses={int(k): Pose2(*v) for k, v in truth["true_poses"].items()},
                        path_ids=tuple(truth["path_ids"]), routes=(), reused=True)


def _truth_key(sim_config: SimConfig, route_names: list[str], camera: CameraModel,
               join: bool) -> dict[str, Any]:
    """What a memory stored by :func:`teach_memory` was taught from (``teach.json``'s key)."""
    from shared.calibration import camera_to_dict

    key: dict[str, Any] = {"world": sim_config.world, "seed": sim_config.seed,
                           "routes": route_names, "camera": camera_to_dict(camera)}
    if not join:  # absent when joined, so that folders taught before the flag still match
        key["joined"] = False
    return key


def _stored_truth(folder: Path, key: dict[str, Any]) -> dict[str, Any] | None:
    """``folder/teach.json`` when ``folder/memory`` holds a memory taught for ``key``; None
    when it holds no memory.

    Raises:
        InputError: ``folder/memory`` holds a memory taught otherwise, or without
            ``teach.json``.
    """
    from shared.memory.store import MANIFEST_NAME

    directory = folder / "memory"
    if not (directory / MANIFEST_NAME).exists():
        return None
    stored = _read_truth(folder / TRUTH_NAME)
    if stored is None or stored.get("key") != key:
        raise InputError(directory, "holds a memory taught with another world, seed, routes "
                                    "or camera (or without teach.json): remove it or choose "
                                    "another --out")
    return stored


def _read_truth(path: Path) -> dict[str, Any] | None:
    """The stored ``teach.json``, or None when it is missing or not a JSON object."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None
