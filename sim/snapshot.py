"""The simulator showcase: one fisheye frame, a top-down map and the ground truth, in a folder."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from shared.atomic_file import write_bytes_atomic, write_text_atomic
from shared.camera_model import CameraModel
from shared.errors import InputError
from shared.pose import Pose2
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer, RenderedFrame
from sim.simulation import Simulation
from sim.topdown import draw_topdown
from sim.world import World, load_world


@dataclass(frozen=True, slots=True)
class Snapshot:
    """What :func:`take_snapshot` wrote.

    Attributes:
        frame_path: the fisheye frame (grey PNG).
        map_path: the top-down map (colour PNG).
        json_path: pose, counts and the visible landmarks' ground truth.
        summary: the JSON document's content.
    """

    frame_path: Path
    map_path: Path
    json_path: Path
    summary: dict[str, Any]


def take_snapshot(
    config: SimConfig, camera: CameraModel, out_dir: Path, pose: Pose2 | None = None,
    world: World | None = None,
) -> Snapshot:
    """Build the world, place the robot, render one frame and write the showcase files.

    Args:
        config: the simulation (world, seed, people, renderer, mount).
        camera: the simulated lens.
        out_dir: folder for ``frame.png``, ``map.png`` and ``snapshot.json`` (created).
        pose: where to put the robot; None = the world's start pose.
        world: the world to film (a changed one: :mod:`sim.scene_change`); None =
            ``config.world``.

    Raises:
        ConfigError: unknown or malformed world, or a pose inside an obstacle.
        InputError: the output folder cannot be written.
    """
    sim = Simulation(load_world(config.world) if world is None else world, config)
    if pose is not None:
        sim.place_robot(pose)
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    frame = renderer.render(sim)
    topdown = draw_topdown(sim, frame, camera.fov_deg)

    summary = _summary(config, camera, sim, renderer, frame)
    if renderer.effects.last is not None:
        reading = renderer.effects.last
        summary["sensor"] = {"exposure_ms": round(reading.exposure_s * 1e3, 3),
                             "gain": round(reading.gain, 3), "blur_px": round(reading.blur_px, 2),
                             "mean_grey": round(reading.mean_grey, 1)}
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(out_dir, f"cannot create output folder: {e.strerror}") from None
    frame_path, map_path, json_path = (
        out_dir / "frame.png",
        out_dir / "map.png",
        out_dir / "snapshot.json",
    )
    _write_png(frame_path, frame.image)
    _write_png(map_path, topdown)
    write_text_atomic(json_path, json.dumps(summary, indent=2) + "\n")
    return Snapshot(frame_path, map_path, json_path, summary)


def _summary(
    config: SimConfig,
    camera: CameraModel,
    sim: Simulation,
    renderer: FisheyeRenderer,
    frame: RenderedFrame,
) -> dict[str, Any]:
    x, y, yaw = frame.pose_w
    return {
        "world": sim.world.name,
        "seed": config.seed,
        "t_ns": frame.t_ns,
        "pose_w": {"x_m": round(x, 4), "y_m": round(y, 4), "yaw_deg": round(math.degrees(yaw), 3)},
        "camera": {"width": camera.width, "height": camera.height, "fov_deg": camera.fov_deg},
        "landmarks_total": renderer.landmark_count,
        "visible_landmarks": int(frame.visible_ids.shape[0]),
        "people": int(config.people.count),
        "illumination_gain": round(frame.illumination_gain, 4),
        "visible": [
            {
                "id": int(i),
                "u_px": round(float(p[0]), 3),
                "v_px": round(float(p[1]), 3),
                "distance_m": round(float(d), 3),
            }
            for i, p, d in zip(
                frame.visible_ids, frame.visible_pixels_xy, frame.visible_distances_m, strict=True
            )
        ],
    }


def _write_png(path: Path, image: npt.NDArray[np.uint8]) -> None:
    ok, data = cv2.imencode(".png", image)
    if not ok:
        raise RuntimeError(f"{path}: PNG encoding failed")
    write_bytes_atomic(path, data.tobytes())
