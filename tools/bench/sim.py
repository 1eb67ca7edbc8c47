"""``vmnav bench sim``: rendering and physics speed, projection agreement, camera-model accuracy.

Frame time = the physics of one frame period (fixed steps) + rendering one frame
(textured ray casting, people, the post-process stage: illumination, noise),
measured per frame while a scripted driver moves the robot along one of the
world's routes. The caller pins the process to one core.

Projection agreement: in every tenth frame, the corners of the pictures in view
(within 4 m) are found in the rendered image, sub-pixel, from their two edges, and
compared with the camera model's projection of their 3D points
(:func:`tools.bench.corners.picture_corner_errors_px`).
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
from tools.bench.corners import picture_corner_errors_px

RENDER_FPS_TARGET = 60.0
CORNER_RANGE_M = 4.0
"""Picture corners farther than this are too small on the image to refine, m."""

def bench_render(
    config: SimConfig, camera: CameraModel, frames: int = 300, warmup: int = 10
) -> dict[str, Any]:
    """Time physics + rendering per frame along the world's first route.

    Returns:
        JSON-ready figures: ``render_fps_median`` (frames per second from the
        median frame time, physics included), frame/render/physics times in ms
        (median, p90), picture corners in view per frame (median, min, max), and
        the projection agreement of textured corners (median, p90 px).
    """
    world = load_world(config.world)
    sim = Simulation(world, config)
    route = world.routes[0]
    sim.place_robot(route.start_pose())
    driver = PurePursuit(route.waypoints, speed_m_s=0.5)
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    physics_ms, render_ms, visible, errors = [], [], [], []
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
            if k % 10 == 0:
                near = frame.visible_ids[frame.visible_distances_m < CORNER_RANGE_M]
                errors.append(picture_corner_errors_px(
                    frame.image, camera, frame.T_world_cam,
                    renderer.scene.picture_corners_w, near))
        if driver.done:
            driver = PurePursuit(route.waypoints[::-1], speed_m_s=0.5)
    frame_ms = np.add(physics_ms, render_ms)
    err = np.concatenate(errors) if errors else np.zeros(0)
    return {
        "world": world.name,
        "route": route.name,
        "frames": frames,
        "image_size": [camera.width, camera.height],
        "picture_corners_total": int(renderer.scene.picture_corners_w.shape[0] * 4),
        "visible_corners_median": float(np.median(visible)),
        "visible_corners_min": int(np.min(visible)),
        "visible_corners_max": int(np.max(visible)),
        "corners_refined": int(err.shape[0]),
        "corner_error_px_median": round(float(np.median(err)), 3) if err.size else None,
        "corner_error_px_p90": round(float(np.percentile(err, 90)), 3) if err.size else None,
        "corner_error_px_target": 0.5,
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
