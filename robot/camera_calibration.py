"""Calibrating the fisheye camera from chessboard images, with ``cv2.omnidir``.

Two steps, both free of files and argparse (``vmnav calibrate`` does the I/O):

1. :func:`find_board_corners` finds the inner corners of the board in one grey
   image (``cv2.findChessboardCorners``, refined by ``cv2.cornerSubPix``).
2. :func:`calibrate_omnidir` fits the unified sphere model (Mei & Rives, ICRA
   2007) to the corners of all views with ``cv2.omnidir.calibrate``. Its
   initialization (a generic model with xi = 1 fitted per view) can reject views;
   it reports which ones it kept.

Skew is fixed to 0 (no real sensor has skew, and estimating it only adds noise).
The RMS error reported is recomputed with our own :class:`CameraModel` from the
board poses OpenCV returns, so it also checks that the saved model reproduces the
calibration; ``cv2.omnidir.calibrate``'s own return value is a mean error norm,
not an RMS.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.chessboard import Chessboard, corner_spacing_px
from shared.errors import CalibrationError, ShapeError, check_shape

FloatArray = npt.NDArray[np.float64]

#: Fewest views with a detected board that calibration accepts (before and after
#: omnidir's initialization).
MIN_VIEWS = 3

# No CALIB_CB_FAST_CHECK: it misses boards that the full search finds, and the
# full search takes milliseconds.
_FIND_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)
_OMNIDIR_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 1000, 1e-14)


@dataclass(frozen=True, slots=True)
class OmnidirCalibration:
    """The result of :func:`calibrate_omnidir`.

    Attributes:
        camera: the calibrated camera.
        rms_px: RMS reprojection error over all corners of the used views, px.
        used: indices (into the views given) of the views the calibration used,
            ascending; the others were rejected by omnidir's initialization.
        view_rms_px: RMS reprojection error of each used view, px, same order.
    """

    camera: CameraModel
    rms_px: float
    used: tuple[int, ...]
    view_rms_px: tuple[float, ...]


def find_board_corners(image: npt.NDArray[np.uint8], board: Chessboard) -> FloatArray | None:
    """Find the board's inner corners in a grey image, to sub-pixel accuracy.

    The ``cornerSubPix`` window is 0.4 of the smallest spacing between
    neighbouring corners (clamped to 2..11 px half-width), so it never reaches a
    neighbouring corner, even where the fisheye squeezes the board at the rim.

    Args:
        image: (H, W) uint8 grey image.
        board: the chessboard.

    Returns:
        (cols * rows, 2) float64 corner pixels in OpenCV's order (row by row,
        matching :meth:`Chessboard.object_points` up to a symmetry of the grid),
        or ``None`` if the whole board was not found.

    Raises:
        ShapeError: ``image`` is not a 2-D array.
    """
    if image.ndim != 2:
        raise ShapeError(f"image: expected a grey (H, W) image, got shape {image.shape}")
    found, corners = cv2.findChessboardCorners(image, board.pattern_size, flags=_FIND_FLAGS)
    if not found:
        return None
    half = int(np.clip(0.4 * corner_spacing_px(board, corners.reshape(-1, 2)), 2, 11))
    refined = cv2.cornerSubPix(image, corners, (half, half), (-1, -1), _SUBPIX_CRITERIA)
    return refined.reshape(-1, 2).astype(np.float64)


def calibrate_omnidir(
    corners_per_view: Sequence[FloatArray],
    board: Chessboard,
    image_size: tuple[int, int],
    *,
    fov_deg: float,
    where: str | Path,
) -> OmnidirCalibration:
    """Fit the unified sphere model to chessboard corners seen in several views.

    Args:
        corners_per_view: per view, (cols * rows, 2) corner pixels in
            :meth:`Chessboard.object_points` order (as :func:`find_board_corners`
            returns them).
        board: the chessboard.
        image_size: ``(width, height)`` of the images, px.
        fov_deg: full field of view of the lens, degrees (not measurable by
            calibration; it sets the camera's validity masks).
        where: the images' directory or file list, for error messages.

    Returns:
        The camera, its RMS error and the views used.

    Raises:
        ShapeError: a view's corners are not (cols * rows, 2).
        CalibrationError: fewer than :data:`MIN_VIEWS` views are given or survive
            initialization, OpenCV fails, or the fit is not a valid camera.
    """
    if len(corners_per_view) < MIN_VIEWS:
        raise CalibrationError(
            where,
            f"the board was found in {len(corners_per_view)} image(s); need at least {MIN_VIEWS}",
        )
    for k, corners in enumerate(corners_per_view):
        check_shape(f"corners_per_view[{k}]", np.shape(corners), (board.n_corners, 2))
    object_points = board.object_points()
    # omnidir wants one (N, 1, 3) resp. (N, 1, 2) float64 array per view.
    object_list = [object_points.reshape(-1, 1, 3)] * len(corners_per_view)
    image_list = [np.asarray(c, dtype=np.float64).reshape(-1, 1, 2) for c in corners_per_view]
    try:
        _, K, xi, D, rvecs, tvecs, idx = cv2.omnidir.calibrate(
            object_list,
            image_list,
            image_size,
            None,
            None,
            None,
            cv2.omnidir.CALIB_FIX_SKEW,
            _OMNIDIR_CRITERIA,
        )
    except cv2.error as e:
        hint = " (no view passed initialization)" if "empty()" in e.err else ""
        raise CalibrationError(
            where, f"cv2.omnidir.calibrate failed on {len(image_list)} views{hint}: {e.err}"
        ) from None
    # The indices of the views kept, in the order of rvecs and tvecs.
    order = [int(i) for i in np.asarray(idx).ravel()]
    if len(order) < MIN_VIEWS:
        raise CalibrationError(
            where,
            f"cv2.omnidir.calibrate kept {len(order)} of {len(image_list)} views after "
            f"initialization; need at least {MIN_VIEWS} (vary the board's pose more)",
        )
    fx, fy, xi_value = float(K[0, 0]), float(K[1, 1]), float(np.asarray(xi).item())
    finite = np.all(np.isfinite(K)) and np.all(np.isfinite(D))
    if not (finite and fx > 0.0 and fy > 0.0 and xi_value >= 0.0):
        raise CalibrationError(
            where,
            f"calibration diverged to an invalid camera: fx={fx:.6g}, fy={fy:.6g}, "
            f"xi={xi_value:.6g}, D={np.ravel(D)}",
        )
    camera = CameraModel(
        width=image_size[0], height=image_size[1], K=K, xi=xi, D=D, fov_deg=fov_deg
    )
    errors_sq = {}
    for view, rvec, tvec in zip(order, rvecs, tvecs, strict=True):
        R, _ = cv2.Rodrigues(rvec)
        pixels, _ = camera.project(object_points @ R.T + np.ravel(tvec))
        errors_sq[view] = np.sum((pixels - image_list[view].reshape(-1, 2)) ** 2, axis=1)
    used = tuple(sorted(order))
    rms_px = float(np.sqrt(np.mean(np.concatenate([errors_sq[v] for v in used]))))
    view_rms = tuple(float(np.sqrt(np.mean(errors_sq[v]))) for v in used)
    return OmnidirCalibration(camera=camera, rms_px=rms_px, used=used, view_rms_px=view_rms)
