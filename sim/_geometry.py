"""Small vectorized 2D geometry used by the world checks, the landmark field and the free-space map.

Points are ``(N, 2)`` float64 arrays on the floor plan (world frame, m). Segments
are given by their end points ``a``, ``b`` as ``(S, 2)`` arrays.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def point_segment_distances(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance of every point to every segment.

    Args:
        points: (N, 2) points, m.
        a: (S, 2) segment starts, m.
        b: (S, 2) segment ends, m (a segment of zero length is a point).

    Returns:
        (N, S) distances, m.
    """
    d = b - a  # (S, 2)
    length2 = np.einsum("sk,sk->s", d, d)
    rel = points[:, None, :] - a[None, :, :]  # (N, S, 2)
    t = np.einsum("nsk,sk->ns", rel, d) / np.where(length2 > 0, length2, 1.0)
    t = np.clip(t, 0.0, 1.0)
    closest = a[None, :, :] + t[..., None] * d[None, :, :]
    return np.linalg.norm(points[:, None, :] - closest, axis=-1)


def segment_segment_distance(
    p0: FloatArray, p1: FloatArray, a: FloatArray, b: FloatArray
) -> FloatArray:
    """Distance from one segment ``p0 -> p1`` to each of the segments ``a -> b``.

    Zero when they cross; otherwise the smallest end-point-to-segment distance
    (for two segments in the plane the minimum is attained at an end point).

    Args:
        p0, p1: (2,) end points of the query segment, m.
        a, b: (S, 2) end points of the other segments, m.

    Returns:
        (S,) distances, m.
    """
    ends = point_segment_distances(np.stack([p0, p1]), a, b).min(axis=0)
    others = point_segment_distances(np.concatenate([a, b]), p0[None, :], p1[None, :])[:, 0]
    distance = np.minimum(ends, np.minimum(others[: len(a)], others[len(a) :]))
    return np.where(segments_cross(p0, p1, a, b), 0.0, distance)


def segments_cross(
    p0: FloatArray, p1: FloatArray, a: FloatArray, b: FloatArray
) -> npt.NDArray[np.bool_]:
    """Whether segment ``p0 -> p1`` properly crosses each segment ``a -> b`` ((S,) bool)."""

    def side(o: FloatArray, u: FloatArray, v: FloatArray) -> FloatArray:
        return (u[..., 0] - o[..., 0]) * (v[..., 1] - o[..., 1]) - (u[..., 1] - o[..., 1]) * (
            v[..., 0] - o[..., 0]
        )

    d1 = side(a, b, p0[None, :])
    d2 = side(a, b, p1[None, :])
    d3 = side(p0[None, :], p1[None, :], a)
    d4 = side(p0[None, :], p1[None, :], b)
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def box_corners(
    center: tuple[float, float], size: tuple[float, float], yaw_deg: float
) -> FloatArray:
    """Corners of a rotated rectangle, counter-clockwise.

    Args:
        center: (x, y) of the centre, m.
        size: (length along the yaw direction, width across it), m.
        yaw_deg: rotation, counter-clockwise from the world x axis, degrees.

    Returns:
        (4, 2) corners, m, counter-clockwise (so each edge's outward normal is
        its direction turned clockwise).
    """
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    hx, hy = size[0] / 2, size[1] / 2
    local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.asarray(center, dtype=float)


def points_in_polygons(points: FloatArray, corners: FloatArray) -> npt.NDArray[np.bool_]:
    """Whether each point is strictly inside each convex counter-clockwise polygon.

    Args:
        points: (N, 2) points, m.
        corners: (P, K, 2) corners of P convex polygons, counter-clockwise, m.

    Returns:
        (N, P) bool.
    """
    a = corners[None, :, :, :]
    b = np.roll(corners, -1, axis=1)[None, :, :, :]
    p = points[:, None, None, :]
    cross = (b[..., 0] - a[..., 0]) * (p[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (
        p[..., 0] - a[..., 0]
    )
    return np.all(cross > 0, axis=2)


def polygon_edges(corners: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Edges of polygons as segments: (P*K, 2) starts and ends, polygon by polygon."""
    return corners.reshape(-1, 2), np.roll(corners, -1, axis=1).reshape(-1, 2)
