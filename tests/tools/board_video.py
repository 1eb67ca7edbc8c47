"""A calibration video for ``vmnav calibrate --capture``: rendered chessboard views through a
lens, as an MJPEG AVI that ``cv2.VideoCapture`` reads like a camera."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from shared.camera_model import CameraModel
from sim.checkerboard import write_synthetic_set


def render_board_views(folder: Path, camera: CameraModel, n_views: int) -> list[np.ndarray]:
    """``n_views`` views of the 9x6, 25 mm board through ``camera`` (grey, h x w uint8)."""
    paths = write_synthetic_set(folder, camera, np.random.default_rng(3), n_views)
    return [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in paths]


def write_video(path: Path, frames: list[np.ndarray]) -> None:
    """``frames`` (grey, all one size) as an MJPEG AVI at 15 frames/s."""
    height, width = frames[0].shape
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 15.0,
                             (width, height), isColor=False)
    for frame in frames:
        writer.write(frame)
    writer.release()


def board_video(path: Path, views: list[np.ndarray]) -> Path:
    """The views, each held for three frames, between frames of the lens without a board
    (what a person moving a board in front of the camera gives); returns ``path``."""
    empty = np.where(views[0] > 0, 128, 0).astype(np.uint8)
    frames = [empty] * 3
    for view in views:
        frames += [view] * 3 + [empty]
    write_video(path, frames)
    return path
