"""Teach a route of a simulated world in lock-step, keeping the true poses.

The loop couples the simulator and the robot's code, so it lives in the harness (robot/
never imports sim/, sim/ never imports robot/):

1. :func:`sim.teach_recording.record_drive` drives the simulated robot along the
   route with the scripted human-like :class:`sim.teach_driver.TeachDriver`, in
   lock-step, one rendered frame per camera period;
2. each frame's image and the body's wheel odometry (not the truth) go to
   :class:`robot.teach.KeyImageSelector`;
3. the caller adds the key images to a memory as a new path (``vmnav teach --sim``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from shared.errors import InputError
from shared.pose import Pose2

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.teach import SelectedKeyImage
    from robot.vision.features import GreyImage
    from shared.camera_model import CameraModel
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
        true_poses: the true robot pose of each key image, world frame (evaluation only).
        frames: frames recorded.
        sim_time_s: simulated duration of the drive, s.
    """

    route: Route
    key_images: tuple[SelectedKeyImage, ...]
    true_poses: tuple[Pose2, ...]
    frames: int
    sim_time_s: float


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
