"""Two-view triangulation of unit bearings with a known relative pose.

Convention: a point seen along ``f_a`` from view a and along ``f_b`` from view b
satisfies ``X_b = R_b_a X_a + t_b_a``, so view a's centre sits at ``t_b_a`` in
frame b. The two rays are ``t + lambda_a d_a`` (``d_a = R_b_a f_a``) and
``lambda_b f_b``. Their closest points follow from crossing ``lambda_b f_b -
lambda_a d_a = t`` with ``d_a`` and with ``f_b`` (n = f_b x d_a)::

    lambda_b = (t x d_a) . n / |n|^2,    lambda_a = (t x f_b) . n / |n|^2

The point is the inverse-depth weighted midpoint of the two closest points (Lee &
Civera, "Triangulation: why optimize?", BMVC 2019, sec. 3: weights 1/lambda make
the midpoint close to the angular-error optimum), and a depth is positive when
the point is in front along the ray, which is right for rays beyond 90 degrees too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.errors import check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class RayDepths:
    """Where two rays pass closest to each other.

    Attributes:
        depth_a: (N,) distance along ray a (from a's centre, units of ``t_b_a``);
            negative behind the camera, NaN for parallel rays.
        depth_b: (N,) the same along ray b.
        parallax_rad: (N,) angle between the two rays once rotated into one frame,
            rad in [0, pi] (0: a point at infinity or no translation).
    """

    depth_a: FloatArray
    depth_b: FloatArray
    parallax_rad: FloatArray


@dataclass(frozen=True, eq=False)
class Triangulation:
    """Points triangulated from two views.

    Attributes:
        points_b: (N, 3) float64 points in frame b, units of ``t_b_a`` (NaN for parallel rays).
        depths: the ray depths and parallax each point came from.
        in_front: (N,) bool, both depths are positive.
    """

    points_b: FloatArray
    depths: RayDepths
    in_front: BoolArray


def _check_pair(R_b_a: FloatArray, t_b_a: FloatArray, bearings_a: FloatArray,
                bearings_b: FloatArray) -> None:
    check_shape("R_b_a", np.shape(R_b_a), (3, 3))
    check_shape("t_b_a", np.shape(t_b_a), (3,))
    check_shape("bearings_a", np.shape(bearings_a), (None, 3))
    check_shape("bearings_b", np.shape(bearings_b), (len(bearings_a), 3))


def skew(v: FloatArray) -> FloatArray:
    """(3, 3) cross-product matrix: ``skew(v) @ w == np.cross(v, w)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def cross_rows(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise cross products of (N, 3) arrays (faster than ``np.cross`` for small N)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def ray_depths(
    R_b_a: FloatArray, t_b_a: FloatArray, bearings_a: FloatArray, bearings_b: FloatArray
) -> RayDepths:
    """Depths along both rays of each correspondence, and their parallax.

    Args:
        R_b_a: (3, 3) rotation, frame a -> frame b.
        t_b_a: (3,) view a's centre in frame b (any length; depths are in its units).
        bearings_a: (N, 3) unit rays in frame a.
        bearings_b: (N, 3) unit rays in frame b.

    Returns:
        The depths and parallax angles.

    Raises:
        ShapeError: an argument has the wrong shape.
    """
    _check_pair(R_b_a, t_b_a, bearings_a, bearings_b)
    return ray_depths_unchecked(np.asarray(R_b_a, dtype=np.float64),
                                np.asarray(t_b_a, dtype=np.float64),
                                np.asarray(bearings_a, dtype=np.float64),
                                np.asarray(bearings_b, dtype=np.float64))


def ray_depths_unchecked(R_b_a: FloatArray, t_b_a: FloatArray, bearings_a: FloatArray,
                         bearings_b: FloatArray) -> RayDepths:
    """:func:`ray_depths` without the shape checks, for inner loops (float64 arrays only)."""
    d_a = bearings_a @ R_b_a.T
    f_b = bearings_b
    n = cross_rows(f_b, d_a)
    nn = np.einsum("ij,ij->i", n, n)
    t_cross = skew(t_b_a).T  # v @ t_cross == t x v
    with np.errstate(divide="ignore", invalid="ignore"):
        depth_b = np.einsum("ij,ij->i", d_a @ t_cross, n) / nn
        depth_a = np.einsum("ij,ij->i", f_b @ t_cross, n) / nn
    parallax = np.arctan2(np.sqrt(nn), np.einsum("ij,ij->i", f_b, d_a))
    return RayDepths(depth_a=depth_a, depth_b=depth_b, parallax_rad=parallax)


def triangulate_bearings(
    R_b_a: FloatArray, t_b_a: FloatArray, bearings_a: FloatArray, bearings_b: FloatArray
) -> Triangulation:
    """Triangulate correspondences between two views (inverse-depth weighted midpoint).

    Args:
        R_b_a: (3, 3) rotation, frame a -> frame b.
        t_b_a: (3,) view a's centre in frame b; sets the units of the points.
        bearings_a: (N, 3) unit rays in frame a.
        bearings_b: (N, 3) unit rays in frame b.

    Returns:
        Points in frame b; callers filter on ``in_front`` and ``depths.parallax_rad``.

    Raises:
        ShapeError: an argument has the wrong shape.
    """
    depths = ray_depths(R_b_a, t_b_a, bearings_a, bearings_b)
    t = np.asarray(t_b_a, dtype=np.float64)
    d_a = np.asarray(bearings_a, dtype=np.float64) @ np.asarray(R_b_a, dtype=np.float64).T
    on_a = t + depths.depth_a[:, None] * d_a
    on_b = depths.depth_b[:, None] * np.asarray(bearings_b, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        in_front = (depths.depth_a > 0) & (depths.depth_b > 0)
        # Weights 1/depth_a and 1/depth_b, written without dividing by either.
        total = (depths.depth_a + depths.depth_b)[:, None]
        points = (depths.depth_b[:, None] * on_a + depths.depth_a[:, None] * on_b) / total
    return Triangulation(points_b=points, depths=depths, in_front=in_front)
