"""Small synthetic key images and memories for the visual-memory tests (no simulator)."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from shared.camera_model import CameraModel
from shared.memory import Junction, KeyframeRecord, VisualMemory, write_memory

#: Descriptor length of the synthetic key images (5x5 patches).
PATCH_LENGTH = 25


def small_camera(width: int = 160, height: int = 120) -> CameraModel:
    """A fisheye camera with small images, so that tests stay fast."""
    f = width / 2.0
    K = [[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]]
    return CameraModel(width=width, height=height, K=K, xi=1.2, fov_deg=185.0)


def make_record(
    rng: np.random.Generator,
    camera: CameraModel,
    t_ns: int,
    distance_m: float,
    n_features: int = 12,
) -> KeyframeRecord:
    """A key image of random grey levels with random corners and unit-norm descriptors."""
    image = rng.integers(0, 256, size=(camera.height, camera.width), dtype=np.uint8)
    pixels_xy = rng.uniform([0.0, 0.0], [camera.width - 1, camera.height - 1], size=(n_features, 2))
    patches = rng.standard_normal((n_features, PATCH_LENGTH)).astype(np.float32)
    patches -= patches.mean(axis=1, keepdims=True)
    patches /= np.linalg.norm(patches, axis=1, keepdims=True)
    odom_pose = (distance_m, float(rng.normal(0.0, 0.05)), float(rng.normal(0.0, 0.1)))
    return KeyframeRecord(
        t_ns=t_ns,
        odom_pose=odom_pose,
        distance_m=distance_m,
        image=image,
        pixels_xy=pixels_xy,
        patches=patches,
    )


def make_records(
    rng: np.random.Generator, camera: CameraModel, spacings_m: Sequence[float], t0_ns: int = 0
) -> list[KeyframeRecord]:
    """``len(spacings_m) + 1`` key images, the i-th step ``spacings_m[i]`` metres long, each
    with random tracks from the one before."""
    distances_m = np.concatenate([[0.0], np.cumsum(spacings_m)])
    records = [
        make_record(rng, camera, t0_ns + i * 1_000_000_000, float(d))
        for i, d in enumerate(distances_m)
    ]
    return records[:1] + [
        replace(record, tracked_from_previous=random_tracks(rng, len(previous.pixels_xy),
                                                            len(record.pixels_xy)))
        for previous, record in itertools.pairwise(records)
    ]


def random_tracks(rng: np.random.Generator, n_previous: int, n_current: int) -> np.ndarray:
    """(K, 2) int64 distinct corner pairs, K about half the smaller corner count."""
    k = min(n_previous, n_current) // 2
    return np.column_stack([rng.permutation(n_previous)[:k], rng.permutation(n_current)[:k]])


def loop_memory(rng: np.random.Generator, camera: CameraModel | None = None) -> VisualMemory:
    """Two paths closing a loop: corridor 0-3 (0.5 m steps), then back 4-6 (1 m steps).

    Junctions: 3 <-> 4 (the corridor's end is where "back" starts) and 6 <-> 0.
    """
    memory = VisualMemory(camera or small_camera())
    memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 0.5]))
    memory.add_path("back", make_records(rng, memory.camera, [1.0, 1.0], t0_ns=10**10))
    memory.add_junction(Junction(from_id=3, to_id=4, matches=80))
    memory.add_junction(Junction(from_id=6, to_id=0, matches=75))
    return memory


def shared_stretch_memory(rng: np.random.Generator) -> VisualMemory:
    """A corridor, 6 m (ids 0-12, 0.5 m steps), and a loop that leaves it at its key image 2
    and runs along it for 4 m (ids 13-21, its own odometry frame from 0): junction 2 <-> 13,
    so key images 2 m past it on each path (6 and 17) are one place."""
    memory = VisualMemory(small_camera())
    memory.add_path("corridor", make_records(rng, memory.camera, [0.5] * 12))
    memory.add_path("loop", make_records(rng, memory.camera, [0.5] * 8, t0_ns=10**11))
    memory.add_junction(Junction(from_id=2, to_id=13, matches=90))
    return memory


def folder_bytes(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder``, at any depth, by path relative to it: its bytes (to show
    that a command changed none)."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def memory_without_manifest(folder: Path, rng: np.random.Generator) -> dict[str, bytes]:
    """Store :func:`loop_memory` in ``folder``, then delete its ``manifest.json`` (a memory a
    user damaged); returns the files left (:func:`folder_bytes`: 21 key image files)."""
    write_memory(folder, loop_memory(rng))
    (folder / "manifest.json").unlink()
    return folder_bytes(folder)
