"""Drawing the built-in set's composed textures: frames, doors, windows, shelves, signs.

Each function takes grey pictures (uint8, (H, W)) and returns one; the surfaces
(wood, brick, glass) are photographs from :mod:`tools.textures.sources`, the layout
(frames, panels, text) is drawn with OpenCV.
"""

from __future__ import annotations

import cv2
import numpy as np

from tools.textures.sources import GreyImage

FRAME_LEVEL = 40  # a dark picture frame
MOUNT_LEVEL = 235  # the white mount between frame and picture


def framed(image: GreyImage, frame_frac: float = 0.04, mount_frac: float = 0.05) -> GreyImage:
    """``image`` in a white mount and a dark frame, fractions of its shorter side."""
    side = min(image.shape)
    mount = max(2, round(mount_frac * side))
    frame = max(2, round(frame_frac * side))
    out = cv2.copyMakeBorder(image, mount, mount, mount, mount, cv2.BORDER_CONSTANT,
                             value=MOUNT_LEVEL)
    return cv2.copyMakeBorder(out, frame, frame, frame, frame, cv2.BORDER_CONSTANT,
                              value=FRAME_LEVEL)


def tiled(pattern: GreyImage, width_px: int, height_px: int) -> GreyImage:
    """``pattern`` repeated to cover ``width_px`` x ``height_px`` (cropped at the ends)."""
    h, w = pattern.shape
    reps = (-(-height_px // h), -(-width_px // w))
    return np.ascontiguousarray(np.tile(pattern, reps)[:height_px, :width_px])
