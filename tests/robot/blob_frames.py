"""Synthetic teach frames whose corners come and go on a known schedule (no simulator).

Each *point* is a small smooth saddle, x y exp(-(x^2 + y^2) / (2 sigma^2)) (one
Harris corner at its centre, where ``cv2.cornerSubPix`` converges as on a
chessboard), at its own cell of a grid; a frame shows the points its schedule says are visible.
Cells are far enough apart that a point can only ever match itself in a small
tracking window, and a cell is not reused while a track of it could be alive, so
the points shared between frames are known exactly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from shared.camera_model import CameraModel

WIDTH_PX = 320
HEIGHT_PX = 200
CELL_PX = 26
"""Grid spacing: more than the tracking window's 20 px (6.59 degrees on :func:`blob_camera`)."""
COLUMNS = 11
ROWS = 7
BACKGROUND = 100.0
SADDLE_AMPLITUDE = 60.0
SADDLE_SIGMA_PX = 2.0
NOISE_SIGMA = 1.0


def blob_camera() -> CameraModel:
    """A 320x200 crop of the default lens (about 174 px/rad everywhere, so the tracking
    window's 6.59 degrees are about 20 px) whose every pixel sees the world."""
    xi = 1.6
    f = 174.0 * (1.0 + xi)
    K = [[f, 0.0, (WIDTH_PX - 1) / 2.0], [0.0, f, (HEIGHT_PX - 1) / 2.0], [0.0, 0.0, 1.0]]
    return CameraModel(width=WIDTH_PX, height=HEIGHT_PX, K=K, xi=xi, fov_deg=185.0)


def cell_centre(point: int) -> tuple[float, float]:
    """The pixel centre (x, y) of a point's cell (cells are reused cyclically)."""
    cell = point % (COLUMNS * ROWS)
    return 20.0 + CELL_PX * (cell % COLUMNS), 20.0 + CELL_PX * (cell // COLUMNS)


def _saddle_stamp() -> np.ndarray:
    half = 4 * int(SADDLE_SIGMA_PX) + 1
    v, u = np.mgrid[-half : half + 1, -half : half + 1] / SADDLE_SIGMA_PX
    return SADDLE_AMPLITUDE * u * v * np.exp(-(u * u + v * v) / 2.0)


_STAMP = _saddle_stamp()


def render(visible: Sequence[int], rng: np.random.Generator) -> np.ndarray:
    """(200, 320) uint8 frame showing the saddles of the ``visible`` points, with a little noise."""
    image = rng.normal(BACKGROUND, NOISE_SIGMA, (HEIGHT_PX, WIDTH_PX))
    half = _STAMP.shape[0] // 2
    for point in visible:
        cx, cy = (int(c) for c in cell_centre(point))
        image[cy - half : cy + half + 1, cx - half : cx + half + 1] += _STAMP
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def frames_from_schedule(
    visible_per_frame: Sequence[Sequence[int]], rng: np.random.Generator, step_m: float = 0.1
) -> list[tuple[int, np.ndarray, tuple[float, float, float]]]:
    """Teach frames (t_ns, image, odom_pose): frame k at k/15 s, driven ``step_m`` along x each."""
    return [
        (k * 66_666_667, render(visible, rng), (k * step_m, 0.0, 0.0))
        for k, visible in enumerate(visible_per_frame)
    ]
