"""Small memories of random textures, each key image a distinct place (no simulator).

A query of place k is the same texture seen again: shifted a few pixels, with
another gain, offset and noise (:func:`sim.synthetic.image_pairs.warped_pair`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robot.config import FeatureConfig
from robot.vision.features import pixels_per_radian
from robot.vision.front_end import make_front_end, stored_descriptors
from shared.camera_model import CameraModel
from shared.memory import KeyframeRecord, VisualMemory
from sim.synthetic.image_pairs import similarity_homography, warped_pair
from tests.shared.memory.builders import small_camera


def _deg_on_small_camera(px: float) -> float:
    return math.degrees(px / pixels_per_radian(small_camera()))


#: The textures are drawn in pixels of a small, very wide lens (36 px/rad): the paper's front
#: end with its reference pixel sizes there (11 px patches 8 px apart).
FEATURES = FeatureConfig(method="harris-zncc", patch_size_deg=_deg_on_small_camera(11.0),
                         min_distance_deg=_deg_on_small_camera(8.0))


@dataclass(frozen=True, eq=False)
class Place:
    """A key image and a second view of the same texture."""

    key_image: np.ndarray
    query: np.ndarray


def make_places(
    rng: np.random.Generator, count: int, camera: CameraModel, shift_px: float = 3.0
) -> list[Place]:
    """``count`` random textures, each with a view shifted by ``shift_px`` and relit."""
    H = similarity_homography((shift_px, -shift_px / 2), centre_xy=(camera.width / 2, 60.0))
    places = []
    for _ in range(count):
        pair = warped_pair(rng, H, camera.width, camera.height, gain=1.1, offset=-8.0)
        places.append(Place(pair.image_a, pair.image_b))
    return places


def record_of(image: np.ndarray, camera: CameraModel, index: int) -> KeyframeRecord:
    """A key image record of ``image`` (corners inside the lens), 1 s and 0.5 m apart."""
    features = make_front_end(FEATURES, camera).describe(image)
    return KeyframeRecord(
        t_ns=index * 1_000_000_000,
        odom_pose=(0.5 * index, 0.0, 0.0),
        distance_m=0.5 * index,
        image=image,
        pixels_xy=np.array(features.pixels_xy),
        patches=stored_descriptors(features),
    )


def memory_of(
    paths: dict[str, list[np.ndarray]], camera: CameraModel | None = None
) -> VisualMemory:
    """A memory with one path per entry, its key images in order."""
    camera = camera or small_camera()
    memory = VisualMemory(camera)
    for name, images in paths.items():
        memory.add_path(name, [record_of(image, camera, i) for i, image in enumerate(images)])
    return memory
