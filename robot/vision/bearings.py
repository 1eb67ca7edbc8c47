"""Matched pixels to unit bearings in the level camera frame.

The camera model's exact lift (valid beyond 90 degrees off axis), then the fixed
camera-to-level rotation of the mount (:func:`shared.camera_mount.rotation_level_cam`),
so that y is vertical and two views on a flat floor differ by an upright planar
motion (reference visual-navigation.md, sec. 4.4, step 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.errors import check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class LevelBearings:
    """Unit rays of pixels in the level camera frame (x right, y down, z forward, level).

    Attributes:
        bearings: (N, 3) float64 unit rows (the row is (0, 0, 1) where not valid,
            so downstream checks never see NaN; select rows with ``valid``).
        valid: (N,) bool, the pixel lifts to a valid ray of the camera model.
    """

    bearings: FloatArray
    valid: BoolArray


def level_bearings(camera: CameraModel, pixels_xy: npt.ArrayLike,
                   R_level_cam: FloatArray) -> LevelBearings:
    """Lift pixels to unit bearings and rotate them into the level camera frame.

    Args:
        camera: the lens model the pixels come from.
        pixels_xy: (N, 2) pixel coordinates, px.
        R_level_cam: (3, 3) rotation camera -> level frame
            (:func:`shared.camera_mount.rotation_level_cam` of the mount).

    Returns:
        Bearings and their validity.

    Raises:
        ShapeError: ``pixels_xy`` is not (N, 2) or ``R_level_cam`` not (3, 3).
    """
    check_shape("R_level_cam", np.shape(R_level_cam), (3, 3))
    bearings_c, valid = camera.lift(pixels_xy)
    bearings = bearings_c @ np.asarray(R_level_cam, dtype=np.float64).T
    bearings[~valid] = (0.0, 0.0, 1.0)
    return LevelBearings(bearings=bearings, valid=valid)
