"""The cost of the simulated camera's flaws and of drawing people, for ``vmnav bench sim``.

Drives the robot along the world's first route as the render benchmark does, with
three people coming the other way along it (then walking about), and times per frame,
separately from the rest of the render:

- the sensor stage (:class:`sim.camera_effects.CameraEffects.apply`: blur, vignetting,
  exposure, noise, clipping) on the rendered frame, with the body's true motion;
- drawing the people as textured figures (:class:`sim.person_figure.PersonFigures`).

Times are the thread's CPU time (``time.thread_time_ns``): the cost of the stage on one
core, which other jobs sharing the machine inflate less than wall time. The caller pins
the process to one core.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from shared.camera_model import CameraModel
from shared.camera_mount import camera_pose_world
from sim.camera_effects import CameraEffects, camera_motion
from sim.config import PeopleConfig, SimConfig
from sim.driver import PurePursuit
from sim.person_figure import PersonFigures
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.texture_library import TextureLibrary
from sim.world import load_world

PEOPLE = 3
"""People about during the measurement."""


def _ahead(waypoints: tuple[tuple[float, float], ...], count: int) -> list[tuple[float, float]]:
    """``count`` points along the route's first leg, 2 m apart from 3 m ahead of its start
    (as many as fit), each 0.5 m to alternate sides."""
    (x0, y0), (x1, y1) = waypoints[0], waypoints[1]
    length = math.hypot(x1 - x0, y1 - y0)
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    points = []
    for k in range(count):
        along = min(3.0 + 2.0 * k, 0.9 * length)
        side = 0.5 if k % 2 == 0 else -0.5
        points.append((x0 + along * ux - side * uy, y0 + along * uy + side * ux))
    return points


def bench_camera_effects(config: SimConfig, camera: CameraModel, frames: int = 150,
                         warmup: int = 5) -> dict[str, Any]:
    """Time the sensor stage and the people's figures per frame along the first route.

    Returns:
        JSON-ready figures: ``sensor_ms_median``/``_p90`` (the whole sensor stage),
        ``sensor_blur_px_median``/``_max`` (longest blur in each frame),
        ``sensor_exposure_ms_median``, ``people_ms_median``/``_p90`` (drawing
        ``PEOPLE`` figures, whether or not they are in view) and
        ``people_in_view_frames`` (frames where some figure was drawn).
    """
    config = dataclasses.replace(config, people=PeopleConfig(count=PEOPLE))
    world = load_world(config.world)
    sim = Simulation(world, config)
    route = world.routes[0]
    sim.place_robot(route.start_pose())
    for k, (x, y) in enumerate(_ahead(route.waypoints, PEOPLE)):  # coming the other way
        sim.people.place(k, (x, y), route.waypoints[0])
    driver = PurePursuit(route.waypoints, speed_m_s=0.5)
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    effects = CameraEffects(camera, config.camera_mount, config.sensor, np.random.default_rng(0))
    figures = PersonFigures(camera, TextureLibrary.builtin(), world.lighting.brightness,
                            np.random.default_rng(0))
    sensor_ms, people_ms, blur_px, exposure_ms, in_view = [], [], [], [], 0
    for k in range(frames + warmup):
        cmd = driver.command(sim.body.pose_w)
        sim.body.command(cmd.v_m_s, cmd.omega_rad_s)
        sim.step_until(sim.now_ns + config.frame_period_ns)
        image = renderer.render(sim).image
        motion = camera_motion(sim.body.velocity_base, config.camera_mount)
        T = camera_pose_world(sim.body.pose_w, config.camera_mount)
        canvas = image.copy()
        t0 = time.thread_time_ns()
        effects.apply(image, sim.now_ns, motion)
        t1 = time.thread_time_ns()
        figures.draw_people(sim, canvas, T[:3, :3].T, T[:3, 3])
        t2 = time.thread_time_ns()
        if k >= warmup and effects.last is not None:
            sensor_ms.append((t1 - t0) / 1e6)
            people_ms.append((t2 - t1) / 1e6)
            blur_px.append(effects.last.blur_px)
            exposure_ms.append(effects.last.exposure_s * 1e3)
            in_view += int(not np.array_equal(canvas, image))
        if driver.done:
            driver = PurePursuit(route.waypoints[::-1], speed_m_s=0.5)
    return {
        "sensor_ms_median": round(float(np.median(sensor_ms)), 3),
        "sensor_ms_p90": round(float(np.percentile(sensor_ms, 90)), 3),
        "sensor_blur_px_median": round(float(np.median(blur_px)), 2),
        "sensor_blur_px_max": round(float(np.max(blur_px)), 2),
        "sensor_exposure_ms_median": round(float(np.median(exposure_ms)), 2),
        "people": PEOPLE,
        "people_ms_median": round(float(np.median(people_ms)), 3),
        "people_ms_p90": round(float(np.percentile(people_ms, 90)), 3),
        "people_in_view_frames": in_view,
    }
