"""``vmnav bench sim``: rendering and physics speed, camera-model accuracy.

Frame time = the physics of one frame period (fixed steps) + rendering one
frame, measured per frame while a scripted driver moves the robot along one of
the world's routes. The caller pins the process to one core.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from typing import Any

import cv2
import numpy as np
import pymunk

from shared.camera_model import CameraModel
from sim.config import SimConfig
from sim.driver import PurePursuit
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.world import load_world
from tools.bench.camera_effects import bench_camera_effects

RENDER_FPS_TARGET = 100.0


def bench_render(
    config: SimConfig, camera: CameraModel, frames: int = 300, warmup: int = 10
) -> dict[str, Any]:
    """Time physics + rendering per frame along the world's first route.

    Returns:
        JSON-ready figures: ``render_fps_median`` (frames per second from the
        median frame time, physics included), frame/render/physics times in ms
        (median, p90), and visible landmarks per frame (median, min, max).
    """
    world = load_world(config.world)
    sim = Simulation(world, config)
    route = world.routes[0]
    sim.place_robot(route.start_pose())
    driver = PurePursuit(route.waypoints, speed_m_s=0.5)
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    physics_ms, render_ms, visible = [], [], []
    for k in range(frames + warmup):
        cmd = driver.command(sim.body.pose_w)
        sim.body.command(cmd.v_m_s, cmd.omega_rad_s)
        t0 = time.perf_counter_ns()
        sim.step_until(sim.now_ns + config.frame_period_ns)
        t1 = time.perf_counter_ns()
        frame = renderer.render(sim)
        t2 = time.perf_counter_ns()
        if k >= warmup:
            physics_ms.append((t1 - t0) / 1e6)
            render_ms.append((t2 - t1) / 1e6)
            visible.append(int(frame.visible_ids.shape[0]))
        if driver.done:
            driver = PurePursuit(route.waypoints[::-1], speed_m_s=0.5)
    frame_ms = np.add(physics_ms, render_ms)
    return {
        "world": world.name,
        "route": route.name,
        "frames": frames,
        "image_size": [camera.width, camera.height],
        "landmarks_total": int(sim.landmarks.ids.shape[0]),
        "visible_landmarks_median": float(np.median(visible)),
        "visible_landmarks_min": int(np.min(visible)),
        "visible_landmarks_max": int(np.max(visible)),
        "render_fps_median": round(1000.0 / float(np.median(frame_ms)), 1),
        "render_fps_target": RENDER_FPS_TARGET,
        "frame_ms_median": round(float(np.median(frame_ms)), 3),
        "frame_ms_p90": round(float(np.percentile(frame_ms, 90)), 3),
        "render_ms_median": round(float(np.median(render_ms)), 3),
        "physics_ms_per_frame_median": round(float(np.median(physics_ms)), 3),
        "physics_steps_per_frame": config.frame_period_ns // config.physics_dt_ns,
    }


def camera_accuracy(camera: CameraModel, step_px: float = 0.5) -> dict[str, Any]:
    """Pixel -> bearing -> pixel round trip over the valid image, and agreement with cv2.omnidir.

    Returns:
        ``camera_roundtrip_max_px`` over a ``step_px`` grid of the whole valid image,
        ``camera_roundtrip_max_px_beyond_90deg`` over the part seeing behind the
        image plane, and ``camera_vs_cv2_max_px`` for rays below 90 degrees.
    """
    u, v = np.meshgrid(
        np.arange(0.0, camera.width, step_px), np.arange(0.0, camera.height, step_px)
    )
    pixels = np.column_stack([u.ravel(), v.ravel()])
    bearings, valid = camera.lift(pixels)
    back, ok = camera.project(bearings[valid])
    err = np.hypot(*(back - pixels[valid]).T)
    beyond = bearings[valid][:, 2] < 0.0
    front = bearings[valid][ok & ~beyond]
    cv_pix, _ = cv2.omnidir.projectPoints(
        front.reshape(-1, 1, 3),
        np.zeros(3),
        np.zeros(3),
        camera.K,
        float(camera.xi),
        camera.D.reshape(1, 4),
    )
    ours, _ = camera.project(front)
    return {
        "camera_pixels_checked": int(valid.sum()),
        "camera_max_angle_deg": round(
            math.degrees(float(np.arccos(bearings[valid][:, 2].min()))), 3
        ),
        "camera_roundtrip_max_px": float(err.max()),
        "camera_roundtrip_max_px_beyond_90deg": float(err[beyond].max()) if beyond.any() else None,
        "camera_vs_cv2_max_px": float(np.abs(cv_pix.reshape(-1, 2) - ours).max()),
    }


def versions() -> dict[str, str]:
    """Versions of the libraries the figures depend on."""
    import platform

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "opencv": cv2.__version__,
        "pymunk": pymunk.version,
    }


def run(args: argparse.Namespace) -> int:
    """Print the simulator benchmark's JSON (``vmnav bench sim``)."""
    from tools.bench.cpu import pin_to_one_core
    from tools.harness.sim_args import sim_config_from_args

    config, camera = sim_config_from_args(args)
    cpus = pin_to_one_core()
    result = {"benchmark": "sim", "cpus": cpus, **bench_render(config, camera, frames=args.frames)}
    result.update(camera_accuracy(camera))
    result.update(bench_camera_effects(config, camera, frames=min(args.frames, 150)))
    result["versions"] = versions()
    print(json.dumps(result, indent=2))
    return 0
