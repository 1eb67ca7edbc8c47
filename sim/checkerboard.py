"""Synthetic chessboard images seen through a fisheye :class:`CameraModel`.

Used by the tests of the calibration, and by users who want to try ``vmnav
calibrate`` without a camera::

    import numpy as np
    from shared.camera_model import CameraModel
    from sim.checkerboard import write_synthetic_set

    write_synthetic_set("calib_views", CameraModel.default(), np.random.default_rng(1), 16)
    # then: vmnav calibrate calib_views --pattern 9x6 --square 0.025 -o camera.json

Rendering is ray casting: every pixel corner is lifted to a bearing, the ray is
cut with the board plane, and the board's tone at the hit point is the tone
there. A pixel whose four corners all hit the same square (or all miss the board
the same way) takes that tone outright, which is exact up to the curvature of the
lens inside one pixel because each square is convex. Every other pixel, on an
edge of the pattern or the rim of the image circle, is the mean tone of
``supersample x supersample`` points spread over its area (a box filter), so
edges are anti-aliased and corner detection is sub-pixel accurate. Inside the
image circle those points are bilinear interpolations of the four corners' board
points (less than 0.01 px off the exact lift, and much faster); on the rim each
one is lifted.

The paper carries a white margin of one square around the squares; beyond it is a
mid-grey background; pixels whose ray the lens does not see are black.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from shared.atomic_file import write_bytes_atomic
from shared.camera_model import CameraModel
from shared.chessboard import Chessboard, corner_spacing_px
from shared.errors import InputError, check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Grey levels of the rendered scene.
DARK = 20  #: dark squares
LIGHT = 235  #: light squares and the paper margin
BACKGROUND = 128  #: the world beyond the paper
UNSEEN = 0  #: pixels outside the lens's image circle

#: The board written by :func:`write_synthetic_set`: 9x6 inner corners, 25 mm squares.
DEFAULT_BOARD = Chessboard(cols=9, rows=6, square_m=0.025)

# Cell index given to rays that hit no board cell; far outside any real cell index.
_NO_RAY = np.iinfo(np.int64).min
_MISS = _NO_RAY + 1


@dataclass(frozen=True, slots=True)
class BoardPose:
    """Pose of the board in the camera frame: ``X_c = R_c_b @ X_b + t_c_b``.

    Attributes:
        R_c_b: (3, 3) float64 rotation, board frame -> camera frame.
        t_c_b: (3,) float64 board origin (first inner corner) in the camera frame, m.
    """

    R_c_b: FloatArray
    t_c_b: FloatArray

    def __post_init__(self) -> None:
        R = np.asarray(self.R_c_b, dtype=np.float64)
        t = np.asarray(self.t_c_b, dtype=np.float64)
        check_shape("R_c_b", R.shape, (3, 3))
        check_shape("t_c_b", t.shape, (3,))
        object.__setattr__(self, "R_c_b", R)
        object.__setattr__(self, "t_c_b", t)


@dataclass(frozen=True, slots=True)
class BoardView:
    """One rendered view of the board.

    Attributes:
        image: (height, width) uint8 grey image.
        corners_xy: (cols * rows, 2) float64 true pixels of the inner corners, in
            :meth:`Chessboard.object_points` order.
        corners_valid: (cols * rows,) bool, the corner is seen by the camera.
    """

    image: npt.NDArray[np.uint8]
    corners_xy: FloatArray
    corners_valid: BoolArray


def render_board(
    camera: CameraModel, board: Chessboard, pose: BoardPose, *, supersample: int = 8
) -> BoardView:
    """Render the board seen by ``camera`` from ``pose``, with anti-aliased edges.

    Args:
        camera: the fisheye camera; the image is ``camera.height x camera.width``.
        board: the chessboard.
        pose: where the board is in the camera frame.
        supersample: rays per pixel side on edge pixels (>= 1).

    Returns:
        The image and the true corner pixels.
    """
    if supersample < 1:
        raise ValueError(f"supersample must be >= 1, got {supersample}")
    w, h = camera.width, camera.height
    # Board points seen through the pixel corners, (h + 1, w + 1), decide which
    # pixels are uniform. Corners on the image border count as seen: only the ray
    # matters here.
    gx, gy = np.meshgrid(np.arange(w + 1) - 0.5, np.arange(h + 1) - 0.5)
    rays, _ = camera.lift(np.stack([gx.ravel(), gy.ravel()], axis=1))
    with np.errstate(invalid="ignore"):
        seen = np.all(np.isfinite(rays), axis=1) & (rays[:, 2] > camera.min_z_s)
    grid_xy, grid_hit = _board_xy(rays, seen, pose, board)
    ix, iy = _cells(grid_xy, grid_hit, seen, board)
    ix, iy = ix.reshape(h + 1, w + 1), iy.reshape(h + 1, w + 1)
    same = np.ones((h, w), dtype=bool)
    for cells in (ix, iy):
        top_left = cells[:-1, :-1]
        same &= (top_left == cells[:-1, 1:]) & (top_left == cells[1:, :-1])
        same &= top_left == cells[1:, 1:]
    image = _tones(ix[:-1, :-1], iy[:-1, :-1], board).astype(np.float64)

    # Box filter over the other pixels: supersample^2 samples through each, at
    # offsets (u, v) in (0, 1)^2 from the pixel's top-left corner.
    u, v = np.meshgrid(*[(np.arange(supersample) + 0.5) / supersample] * 2)
    u, v = u.ravel(), v.ravel()
    rows, cols = np.nonzero(~same)
    grid_xy = grid_xy.reshape(h + 1, w + 1, 2)
    grid_hit = grid_hit.reshape(h + 1, w + 1)
    inside = grid_hit[rows, cols] & grid_hit[rows, cols + 1]
    inside &= grid_hit[rows + 1, cols] & grid_hit[rows + 1, cols + 1]
    # Where all four corners see the board, interpolate their board points
    # bilinearly: lens and perspective curve little across one pixel (error
    # < 0.01 px) and lifting is the slow part.
    r, c = rows[inside], cols[inside]
    top_left, top_right = grid_xy[r, c][:, None, :], grid_xy[r, c + 1][:, None, :]
    bottom_left, bottom_right = grid_xy[r + 1, c][:, None, :], grid_xy[r + 1, c + 1][:, None, :]
    top = top_left + u[None, :, None] * (top_right - top_left)
    bottom = bottom_left + u[None, :, None] * (bottom_right - bottom_left)
    xy = (top + v[None, :, None] * (bottom - top)).reshape(-1, 2)
    all_hit = np.ones(xy.shape[0], dtype=bool)
    sx, sy = _cells(xy, all_hit, all_hit, board)
    image[r, c] = _tones(sx, sy, board).reshape(r.size, u.size).mean(axis=1)
    # Elsewhere (the rim of the image circle, the board's horizon) lift every sample.
    r, c = rows[~inside], cols[~inside]
    rays, seen = camera.lift(
        np.stack([c[:, None] - 0.5 + u, r[:, None] - 0.5 + v], axis=2).reshape(-1, 2)
    )
    xy, hit = _board_xy(rays, seen, pose, board)
    sx, sy = _cells(xy, hit, seen, board)
    image[r, c] = _tones(sx, sy, board).reshape(r.size, u.size).mean(axis=1)

    corners_xy, corners_valid = camera.project(board.object_points() @ pose.R_c_b.T + pose.t_c_b)
    return BoardView(
        image=np.rint(image).astype(np.uint8),
        corners_xy=corners_xy,
        corners_valid=corners_valid,
    )


def _board_xy(
    bearings_c: FloatArray, seen: BoolArray, pose: BoardPose, board: Chessboard
) -> tuple[FloatArray, BoolArray]:
    """Where rays from the camera centre meet the board plane.

    Args:
        bearings_c: (N, 3) ray directions, camera frame.
        seen: (N,) bool, the lens sees the ray.

    Returns:
        xy: (N, 2) float64 board coordinates of the hit points, in squares
            (``x_b / square_m``, ``y_b / square_m``); NaN where not hit.
        hit: (N,) bool, the ray is seen and meets the plane in front of the camera.
    """
    R, t = pose.R_c_b, pose.t_c_b
    # Ray X_c = lam * b in board coordinates: X_b = R^T (lam b - t); cut with z_b = 0.
    dirs_b = np.einsum("ni,ij->nj", bearings_c, R)  # R^T b per row; faster than @ here
    origin_b = -(R.T @ t)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = -origin_b[2] / dirs_b[:, 2]
        hit = seen & (lam > 0.0) & np.isfinite(lam)
        xy = (lam[:, None] * dirs_b[:, :2] + origin_b[:2]) / board.square_m
    xy[~hit] = np.nan
    return xy, hit


def _cells(
    xy: FloatArray, hit: BoolArray, seen: BoolArray, board: Chessboard
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Square indices ``floor(xy)`` of board points (see :func:`_board_xy`).

    Returns:
        ix, iy: (N,) int64; both ``_NO_RAY`` where the lens sees no ray and
        ``_MISS`` where the ray misses the board plane.
    """
    # Beyond the paper, merge cells into the 8 convex regions around it: the
    # four-corner test stays exact and the background needs no supersampling.
    with np.errstate(invalid="ignore"):
        cells = np.clip(np.floor(xy), -3, [board.cols + 1, board.rows + 1])
    cells = np.where(hit[:, None], cells, 0.0).astype(np.int64)
    miss = np.where(seen, _MISS, _NO_RAY)
    return np.where(hit, cells[:, 0], miss), np.where(hit, cells[:, 1], miss)


def _tones(
    ix: npt.NDArray[np.int64], iy: npt.NDArray[np.int64], board: Chessboard
) -> npt.NDArray[np.uint8]:
    """Grey level of each cell (see the module docstring for the board layout)."""
    squares = (ix >= -1) & (ix <= board.cols - 1) & (iy >= -1) & (iy <= board.rows - 1)
    paper = (ix >= -2) & (ix <= board.cols) & (iy >= -2) & (iy <= board.rows)
    dark = squares & ((ix + iy) % 2 == 0)
    tone = np.where(paper, LIGHT, BACKGROUND).astype(np.uint8)
    tone[dark] = DARK
    tone[ix == _NO_RAY] = UNSEEN
    return tone


def sample_board_poses(
    camera: CameraModel,
    board: Chessboard,
    rng: np.random.Generator,
    n_views: int,
    *,
    max_tries: int = 1000,
) -> list[BoardPose]:
    """Varied board poses that together cover the centre and the rim of the image.

    View ``k`` puts the board centre at an angle ``theta`` off the optical axis
    drawn from the ``k``-th of ``n_views`` equal strata of ``[0, fov/2 - 12 deg]``,
    so the centre and the rim are both covered whatever the seed. The board
    diagonal spans ``2 beta`` with ``beta`` drawn from ``[18 deg, min(45 deg,
    fov/2 - theta)]``: big boards at the centre, smaller ones towards the rim,
    none so small that ``cv2.findChessboardCorners`` misses it. Azimuth, tilt (up
    to 45 degrees) and the rotation in the board plane are random. A draw is kept
    only when every inner corner and the whole outline of the squares lie at
    least 4 px inside the valid region (the lens's image circle and the image)
    and neighbouring corners are at least 8 px apart; near the rim most draws
    are not, which pushes the kept boards to be small or oblique there, as a
    person holding a board at the rim would hold it.

    Args:
        camera: the camera the poses are for.
        board: the chessboard.
        rng: the random generator (the only source of randomness).
        n_views: how many poses.
        max_tries: draws per view before giving up.

    Returns:
        ``n_views`` poses.

    Raises:
        ValueError: no acceptable pose was found for some view within ``max_tries``.
    """
    half_fov = math.radians(camera.fov_deg / 2.0)
    beta_min, beta_max = math.radians(18.0), math.radians(45.0)
    theta_max = max(half_fov - math.radians(12.0), 0.0)
    outline_b = _outline(board)
    centre_b = np.array([(board.cols - 1) / 2.0, (board.rows - 1) / 2.0, 0.0]) * board.square_m
    half_diagonal = 0.5 * board.square_m * math.hypot(board.cols + 1, board.rows + 1)
    poses = []
    for k in range(n_views):
        for _ in range(max_tries):
            theta = theta_max * (k + rng.uniform()) / n_views
            phi = rng.uniform(0.0, 2.0 * math.pi)
            direction = np.array(
                [math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)]
            )
            beta = rng.uniform(beta_min, max(min(beta_max, half_fov - theta), beta_min))
            distance = half_diagonal / math.tan(beta)
            R_c_b = _facing_rotation(direction) @ _rotation_z(rng.uniform(0.0, 2.0 * math.pi))
            # Tilt the board about an axis in its plane (its x axis after a random spin).
            tilt_axis = R_c_b @ _rotation_z(rng.uniform(0.0, 2.0 * math.pi))[:, 0]
            R_c_b = _rotation_about(tilt_axis, math.radians(rng.uniform(0.0, 45.0))) @ R_c_b
            pose = BoardPose(R_c_b=R_c_b, t_c_b=distance * direction - R_c_b @ centre_b)
            if _acceptable(camera, board, pose, outline_b):
                poses.append(pose)
                break
        else:
            raise ValueError(f"no board pose for view {k} fits the camera in {max_tries} tries")
    return poses


def write_synthetic_set(
    out_dir: str | Path,
    camera: CameraModel,
    rng: np.random.Generator,
    n_views: int,
    board: Chessboard = DEFAULT_BOARD,
) -> list[Path]:
    """Render ``n_views`` board views and write them as ``view_000.png`` ... into ``out_dir``.

    Args:
        out_dir: directory to write into (created if missing).
        camera: the camera to render through.
        rng: the random generator for the poses.
        n_views: how many images.
        board: the chessboard (``vmnav calibrate --pattern 9x6 --square 0.025`` by default).

    Returns:
        The paths written, in order.

    Raises:
        InputError: the folder or a file cannot be written.
    """
    import cv2

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(out, f"cannot create the folder: {e.strerror}") from None
    paths = []
    for k, pose in enumerate(sample_board_poses(camera, board, rng, n_views)):
        path = out / f"view_{k:03d}.png"
        _, png = cv2.imencode(".png", render_board(camera, board, pose).image)
        write_bytes_atomic(path, png.tobytes())
        paths.append(path)
    return paths


def _outline(board: Chessboard, per_square: int = 4) -> FloatArray:
    """Points along the outer edge of the squares area, (M, 3) board frame, m."""
    s = board.square_m
    xs = np.linspace(-s, board.cols * s, per_square * (board.cols + 1) + 1)
    ys = np.linspace(-s, board.rows * s, per_square * (board.rows + 1) + 1)
    edges = [
        np.stack([xs, np.full_like(xs, -s)], axis=1),
        np.stack([xs, np.full_like(xs, board.rows * s)], axis=1),
        np.stack([np.full_like(ys, -s), ys], axis=1),
        np.stack([np.full_like(ys, board.cols * s), ys], axis=1),
    ]
    xy = np.concatenate(edges)
    return np.concatenate([xy, np.zeros((xy.shape[0], 1))], axis=1)


def _acceptable(
    camera: CameraModel, board: Chessboard, pose: BoardPose, outline_b: FloatArray
) -> bool:
    """Whether a pose shows the whole board well enough to be found.

    The outline of the squares and a 4 px ring around each of its points must be
    valid pixels, and neighbouring inner corners at least 8 px apart: below
    that, ``cornerSubPix`` windows are too small to recover from the detector's
    first guess.
    """
    pixels, valid = camera.project(outline_b @ pose.R_c_b.T + pose.t_c_b)
    if not np.all(valid):
        return False
    ring = np.array([[4.0, 0.0], [-4.0, 0.0], [0.0, 4.0], [0.0, -4.0]])
    _, ring_valid = camera.lift((pixels[:, None, :] + ring[None, :, :]).reshape(-1, 2))
    if not np.all(ring_valid):
        return False
    corners, valid = camera.project(board.object_points() @ pose.R_c_b.T + pose.t_c_b)
    return bool(np.all(valid) and corner_spacing_px(board, corners) >= 8.0)


def _facing_rotation(direction: FloatArray) -> FloatArray:
    """A rotation whose z column is the unit ``direction`` (the board seen face on)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(direction[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, direction)
    x /= np.linalg.norm(x)
    y = np.cross(direction, x)
    return np.stack([x, y, direction], axis=1)


def _rotation_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation_about(axis: FloatArray, angle: float) -> FloatArray:
    """Rodrigues' formula for a rotation by ``angle`` rad about the unit ``axis``."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)
