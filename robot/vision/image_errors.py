"""The paper's image errors between the current image and the key image it heads for.

Courbon et al., ICARCV 2008, sec. IV: "we have considered two 'image errors': the
longer distance between an image point and its position in the desired key image
(errImageMax) and the mean distance between those points (errPoints), expressed
in pixels". A key image is taken as reached when one of them falls below a
threshold (the paper switches at errImageMax < 20 px; DESIGN.md sec. 5.7).

Both are computed over the matches given; pass the epipolar inliers to keep
outliers from dominating the maximum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.errors import check_shape


@dataclass(frozen=True, slots=True)
class ImageErrors:
    """Pixel distances between matched points of the current and key images.

    Attributes:
        err_image_max_px: largest distance (the paper's errImageMax), px; inf with no match.
        err_points_px: mean distance (the paper's errPoints), px; inf with no match.
        n_points: number of matches they were computed over.
    """

    err_image_max_px: float
    err_points_px: float
    n_points: int


def image_errors(pixels_current_xy: npt.ArrayLike, pixels_key_xy: npt.ArrayLike) -> ImageErrors:
    """errImageMax and errPoints of matched points.

    Args:
        pixels_current_xy: (N, 2) matched points in the current image, px.
        pixels_key_xy: (N, 2) the same points in the key image, px.

    Returns:
        The errors (inf when N = 0: no evidence that the key image is reached).

    Raises:
        ShapeError: the arrays are not (N, 2) with equal N.
    """
    current = np.asarray(pixels_current_xy, dtype=np.float64)
    key = np.asarray(pixels_key_xy, dtype=np.float64)
    check_shape("pixels_current_xy", current.shape, (None, 2))
    check_shape("pixels_key_xy", key.shape, (len(current), 2))
    if len(current) == 0:
        return ImageErrors(err_image_max_px=np.inf, err_points_px=np.inf, n_points=0)
    distance = np.hypot(*(current - key).T)
    return ImageErrors(err_image_max_px=float(distance.max()),
                       err_points_px=float(distance.mean()), n_points=len(distance))
