"""The fisheye lens's validity mask: which pixels of the image see the world.

Outside the image circle of a fisheye lens the sensor is black; its rim is a
sharp circular edge whose pixelated outline makes Harris corners that stay put
while the robot moves. Detecting features inside this mask (eroded by the patch
size in :func:`robot.vision.features.detect_harris`) keeps them out of tracking
and matching.
"""

from __future__ import annotations

import numpy as np

from robot.vision.features import BoolImage
from shared.camera_model import CameraModel


def lens_mask(camera: CameraModel) -> BoolImage:
    """The pixels whose ray the camera model accepts.

    Args:
        camera: the lens (its field of view bounds the valid rays).

    Returns:
        (H, W) bool, True where the pixel centre lifts to a valid bearing.
    """
    cols, rows = np.meshgrid(
        np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64)
    )
    _, valid = camera.lift(np.column_stack([cols.ravel(), rows.ravel()]))
    return valid.reshape(camera.height, camera.width)
