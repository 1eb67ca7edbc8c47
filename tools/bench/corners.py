"""Finding the corners of pictures in a rendered frame: the projection-agreement measure.

``vmnav bench sim`` and the renderer's tests ask whether a textured corner (a
poster's) appears in the image where the camera model projects its 3D point. A
corner is found in the image, not assumed: each of its two edges is located at
3..10 px from the projected corner, within 2 px across, by the outermost strong
step of the grey profile across the edge (sub-pixel: where the profile crosses
halfway between the greys a pixel either side; frame lines inside the picture do
not count), a line is fitted through those points, and the corner is where the
two lines meet. Unlike ``cv2.cornerSubPix`` this is not pulled by the picture's
content near the corner, nor biased along the corner's bisector. Only clean steps
count: a picture whose border blurs into its wall, or a busy wall, gives no corner.
"""

from __future__ import annotations

import cv2
import numpy as np

from shared.camera_model import CameraModel

EDGE_STEPS_PX = np.arange(3.0, 11.0)
"""Distances from the corner along each edge where the edge is located, px."""
PROFILE_PX = np.arange(-4.0, 4.01, 0.25)
"""Offsets across the edge sampled to find it, px (positive: away from the picture)."""
SEARCH_PX = 2.0
"""The edge is looked for within this distance of where the camera model puts it, px
(farther steps belong to the wall's own texture)."""
MIN_STEP_GREY = 20.0
"""Least grey-level step across an edge point (1 px either side) to use it."""
MIN_EDGE_POINTS = 5
"""Least edge points on each edge to find a corner."""


def picture_corner_errors_px(
    image: np.ndarray,
    camera: CameraModel,
    T_world_cam: np.ndarray,
    corners_w: np.ndarray,
    visible_ids: np.ndarray,
) -> np.ndarray:
    """How far the corners of the pictures in view are, in ``image``, from their projections.

    Corners whose edges are not clean steps against their wall (fewer than
    :data:`MIN_EDGE_POINTS` points on each edge where the grey rises or falls
    monotonically by :data:`MIN_STEP_GREY` or more within a pixel either side), or
    whose edges are nearly parallel in the image, are left out.

    Args:
        image: (H, W) uint8 grey frame.
        camera: the lens that rendered it.
        T_world_cam: (4, 4) the camera pose (camera frame -> world frame).
        corners_w: (P, 4, 3) corners of every picture, world frame, m, in order
            around the picture.
        visible_ids: (K,) ids of the corners in view, ``4 * picture + corner``.

    Returns:
        (M,) float64 distances between the found and the projected corners, px, M <= K.
    """
    grey = image.astype(np.float32)
    to_cam = T_world_cam[:3, :3].T
    centre = T_world_cam[:3, 3]
    errors = []
    for corner_id in np.asarray(visible_ids).tolist():
        picture, k = divmod(int(corner_id), 4)
        quad = corners_w[picture]
        points = np.stack([quad[k],
                           quad[k] + 0.02 * _unit(quad[(k + 1) % 4] - quad[k]),
                           quad[k] + 0.02 * _unit(quad[(k - 1) % 4] - quad[k])])
        pix, ok = camera.project((points - centre) @ to_cam.T)
        if not ok.all():
            continue
        truth = pix[0]
        found = _corner_from_edges(grey, truth, _unit(pix[1] - truth), _unit(pix[2] - truth))
        if found is not None:
            errors.append(float(np.linalg.norm(found - truth)))
    return np.asarray(errors, dtype=np.float64)


def _corner_from_edges(grey: np.ndarray, start: np.ndarray, u0: np.ndarray,
                       u1: np.ndarray) -> np.ndarray | None:
    """The corner where the edges leaving ``start`` along ``u0`` and ``u1`` meet, or None."""
    lines = []
    for u, other in ((u0, u1), (u1, u0)):
        n = np.array([-u[1], u[0]])
        if n @ other > 0:
            n = -n  # across the edge, away from the picture
        points = _edge_points(grey, start, u, n)
        if points.shape[0] < MIN_EDGE_POINTS:
            return None
        vx, vy, x0, y0 = cv2.fitLine(points.astype(np.float32), cv2.DIST_L2, 0, 0.01,
                                     0.01).ravel()
        lines.append((np.array([x0, y0], float), np.array([vx, vy], float)))
    (p0, d0), (p1, d1) = lines
    den = d0[0] * d1[1] - d0[1] * d1[0]
    if abs(den) < 0.2:
        return None
    t = ((p1[0] - p0[0]) * d1[1] - (p1[1] - p0[1]) * d1[0]) / den
    return p0 + t * d0


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _edge_points(grey: np.ndarray, corner: np.ndarray, u: np.ndarray,
                 n: np.ndarray) -> np.ndarray:
    """Sub-pixel points (S, 2) of the edge leaving ``corner`` along ``u``, outward normal ``n``."""
    h, w = grey.shape
    base = corner + EDGE_STEPS_PX[:, None] * u  # (S, 2)
    xy = base[:, None, :] + PROFILE_PX[None, :, None] * n  # (S, L, 2)
    if xy.min() < 1 or xy[..., 0].max() > w - 2 or xy[..., 1].max() > h - 2:
        return np.zeros((0, 2))
    profiles = cv2.remap(grey, xy[..., 0].astype(np.float32), xy[..., 1].astype(np.float32),
                         cv2.INTER_LINEAR)
    grad = np.abs(np.gradient(profiles, axis=1))
    step = PROFILE_PX[1] - PROFILE_PX[0]
    points = []
    for s in range(grad.shape[0]):
        g = grad[s]
        near = np.abs(PROFILE_PX[1:-1]) <= SEARCH_PX
        peaks = np.flatnonzero(near & (g[1:-1] >= 0.5 * g[1:-1][near].max())
                               & (g[1:-1] >= g[:-2]) & (g[1:-1] >= g[2:])) + 1
        if peaks.size == 0:
            continue
        i = int(peaks.max())  # the outermost strong step: the picture's silhouette
        # The edge is where the profile crosses halfway between the picture's grey
        # 1 px inside the step and the wall's grey 1 px outside it (exact for a step
        # blurred by any symmetric kernel, such as the pixel's own area).
        lo, hi = max(i - 4, 0), min(i + 4, len(PROFILE_PX) - 1)
        ramp = profiles[s, lo:hi + 1]
        inside, outside = ramp[0], ramp[-1]
        rising = np.diff(ramp) * np.sign(outside - inside)
        if abs(outside - inside) < MIN_STEP_GREY or (rising < -0.5).any():
            continue  # not one clean step within a pixel either side: a blurred or busy border
        seg = ramp - 0.5 * (inside + outside)
        cross = np.flatnonzero(np.sign(seg[:-1]) != np.sign(seg[1:]))
        if cross.size == 0:
            continue
        j = int(cross[np.argmin(np.abs(cross + lo - i))])
        frac = seg[j] / (seg[j] - seg[j + 1])
        points.append(base[s] + (PROFILE_PX[lo + j] + frac * step) * n)
    return np.asarray(points, dtype=np.float64).reshape(-1, 2)
