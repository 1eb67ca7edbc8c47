"""Legacy landmark patches: the checker-quadrant patches of :mod:`sim.landmarks`, painted
over the textured frame for a world that still asks for them (``landmarks`` densities
above zero). The built-in worlds do not.

Each visible patch is painted far-to-near with ``cv2.warpAffine``: the affine map is
the local Jacobian of the projection (the images of the patch's horizontal and
vertical half-sides), so patches foreshorten and turn with the fisheye distortion,
and their centres land at sub-pixel positions. A patch is culled behind its normal,
outside the lens's field of view, when smaller than ``_MIN_PATCH_PX`` on the image,
or when a wall, furniture or a person hides it (one pymunk segment query each).
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from sim.landmarks import LandmarkField
from sim.simulation import OCCLUDER_FILTER, Simulation
from sim.world import Lighting

FloatArray = npt.NDArray[np.float64]

_MIN_PATCH_PX = 3.0
"""Patches smaller than this on the image (px, longest side) are not drawn."""
NEAR_M = 0.15
"""Landmarks closer than this to the optical centre are not drawn, m."""
_QUERY_END_MARGIN_M = 0.12
"""A line of sight stops this short of its landmark, so the surface carrying it does not hit."""
_NEAR_M = NEAR_M


class PatchPainter:
    """Paints a landmark field's visible patches.

    Args:
        camera: the lens.
        landmarks: the field.
        lighting: the world's brightness and patch contrast.
    """

    def __init__(self, camera: CameraModel, landmarks: LandmarkField, lighting: Lighting) -> None:
        self.camera = camera
        self.landmarks = landmarks
        levels = _texture_pyramid(self._contrast_adjusted(landmarks.textures, lighting))
        self._levels = tuple(level.astype(np.float32) for level in levels)
        self._tangents_h, self._tangents_v = _patch_axes(landmarks.normals_w)

    def visible(
        self, sim: Simulation, R_cam_world: FloatArray, centre_w: FloatArray
    ) -> tuple[npt.NDArray[np.int64], FloatArray, FloatArray, FloatArray]:
        """Visible patches: indices, centres (K, 2) px, distances (K,) m, affine maps (K, 2, 3)."""
        lm = self.landmarks
        rel_w = lm.positions_w - centre_w
        dist = np.sqrt(np.einsum("ij,ij->i", rel_w, rel_w))
        facing = np.einsum("ij,ij->i", lm.normals_w, rel_w) < 0.0
        rel_c = rel_w @ R_cam_world.T
        in_cone = rel_c[:, 2] > self.camera.min_z_s * dist
        idx = np.flatnonzero(facing & in_cone & (dist > _NEAR_M))

        half = 0.5 * lm.sizes_m[idx, None]  # (K, 1) half side of each patch, m
        p0, ok0 = self.camera.project(rel_c[idx])
        ph, okh = self.camera.project(rel_c[idx] + half * (self._tangents_h[idx] @ R_cam_world.T))
        pv, okv = self.camera.project(rel_c[idx] - half * (self._tangents_v[idx] @ R_cam_world.T))
        a = ph - p0  # image of the half-side along the patch's horizontal axis (texture +x)
        b = pv - p0  # image of the half-side along the patch's downward axis (texture +y)
        size_px = 2.0 * np.maximum(np.hypot(a[:, 0], a[:, 1]), np.hypot(b[:, 0], b[:, 1]))
        keep = ok0 & okh & okv & (size_px >= _MIN_PATCH_PX)
        idx, p0, a, b, size_px = idx[keep], p0[keep], a[keep], b[keep], size_px[keep]

        unoccluded = self._unoccluded(sim, idx, centre_w, dist[idx])
        idx, p0, a, b, size_px = (
            idx[unoccluded],
            p0[unoccluded],
            a[unoccluded],
            b[unoccluded],
            size_px[unoccluded],
        )
        affines = np.stack([a, b, p0], axis=2)  # dst = p0 + a * tx + b * ty, (tx, ty) in [-1, 1]
        return idx, p0, dist[idx], affines

    def _unoccluded(
        self, sim: Simulation, idx: npt.NDArray[np.int64], centre_w: FloatArray, dist: FloatArray
    ) -> npt.NDArray[np.bool_]:
        """Which landmarks no wall, furniture or person hides (one pymunk ray query each).

        A query runs on the floor plan from the camera to ``_QUERY_END_MARGIN_M``
        short of the landmark. A hit hides the landmark when the occluder is at
        least as tall as the line of sight where it meets it; when the first hit
        is lower, every hit on the way is checked.
        """
        out = np.ones(idx.shape[0], dtype=bool)
        lm = self.landmarks.positions_w[idx]
        cx, cy, cz = (float(v) for v in centre_w)
        dxy = lm[:, :2] - centre_w[:2]
        d2 = np.hypot(dxy[:, 0], dxy[:, 1])
        far = d2 > _QUERY_END_MARGIN_M
        f = np.where(far, (d2 - _QUERY_END_MARGIN_M) / np.where(far, d2, 1.0), 0.0)
        ends = (centre_w[:2] + f[:, None] * dxy).tolist()
        fractions = f.tolist()
        heights = lm[:, 2].tolist()
        query_first, query_all = sim.space.segment_query_first, sim.space.segment_query
        height_of = sim.occluder_height
        start = (cx, cy)
        for k in np.flatnonzero(far).tolist():
            hit = query_first(start, ends[k], 0.0, OCCLUDER_FILTER)
            if hit is None:
                continue
            rise = heights[k] - cz
            if height_of(hit.shape) >= cz + hit.alpha * fractions[k] * rise:
                out[k] = False
                continue
            # The line of sight passes over the first thing it meets: check everything on the way.
            out[k] = all(
                height_of(info.shape) < cz + info.alpha * fractions[k] * rise
                for info in query_all(start, ends[k], 0.0, OCCLUDER_FILTER)
            )
        return out

    def paint(
        self,
        image: npt.NDArray[np.float32],
        ids: npt.NDArray[np.int64],
        affines: FloatArray,
        dist: FloatArray,
    ) -> None:
        """Warp each patch's texture into ``image``, far to near.

        Args:
            image: (H, W) float32, painted in place.
            ids: (K,) landmark indices.
            affines: (K, 2, 3) columns ``a``, ``b``, ``p0``: texture offset (tx, ty)
                in [-1, 1]^2 lands at ``p0 + a tx + b ty`` (px).
            dist: (K,) distances to the optical centre, m (painting order).
        """
        if ids.shape[0] == 0:
            return
        a, b, p0 = affines[:, :, 0], affines[:, :, 1], affines[:, :, 2]
        size_px = 2.0 * np.maximum(np.hypot(a[:, 0], a[:, 1]), np.hypot(b[:, 0], b[:, 1]))
        level = np.where(size_px >= 12.0, 0, np.where(size_px >= 6.0, 1, 2))
        n = np.array([lvl.shape[1] for lvl in self._levels], dtype=np.float64)[level]
        h, w = image.shape
        ext = np.abs(a) + np.abs(b)  # (K, 2) half extents of the warped patch, px
        lo = np.maximum(np.floor(p0 - ext), 0).astype(np.int64)
        hi = np.minimum(np.ceil(p0 + ext).astype(np.int64) + 1, (w, h))
        # Texture pixel s (centre c = (n - 1) / 2) lands at p0 + (a (sx - c) + b (sy - c)) / (n/2).
        half = (n / 2.0)[:, None]
        c = ((n - 1.0) / 2.0)[:, None]
        M = np.empty((ids.shape[0], 2, 3))
        M[:, :, 0] = a / half
        M[:, :, 1] = b / half
        M[:, :, 2] = p0 - lo - (a + b) * c / half
        levels = self._levels
        for k in np.argsort(-dist):
            (x0, y0), (x1, y1) = lo[k], hi[k]
            if x1 > x0 and y1 > y0:
                cv2.warpAffine(
                    levels[level[k]][ids[k]],
                    M[k],
                    (int(x1 - x0), int(y1 - y0)),
                    dst=image[y0:y1, x0:x1],
                    flags=cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_TRANSPARENT,
                )


    @staticmethod
    def _contrast_adjusted(
        textures: npt.NDArray[np.uint8], lighting: Lighting
    ) -> npt.NDArray[np.uint8]:
        """Textures scaled about the scene's mean grey level by the world's contrast."""
        t = textures.astype(np.float32)
        out = lighting.brightness + lighting.contrast * (t - 128.0)
        return np.clip(out, 0, 255).round().astype(np.uint8)



def _texture_pyramid(textures: npt.NDArray[np.uint8]) -> tuple[npt.NDArray[np.uint8], ...]:
    """Each landmark's texture at 16, 8 and 4 px, area-averaged (no aliasing when shrunk)."""
    n, s, _ = textures.shape
    levels = [textures]
    while levels[-1].shape[1] > 4:
        half = levels[-1].shape[1] // 2
        levels.append(
            levels[-1].reshape(n, half, 2, half, 2).mean(axis=(2, 4)).round().astype(np.uint8)
        )
    assert s == 16, "landmark textures are 16x16"
    return tuple(levels)



def _patch_axes(normals_w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit horizontal and upward in-plane axes of each patch (world frame).

    The horizontal axis is up x normal (to the right as one faces the patch);
    a patch facing straight up or down (ceiling) takes world x instead.

    Returns:
        tangents_h, tangents_v: (N, 3) float64 unit rows.
    """
    up = np.array([0.0, 0.0, 1.0])
    h = np.cross(up, normals_w)
    norm = np.linalg.norm(h, axis=1)
    flat = norm < 1e-6
    h[flat] = np.array([1.0, 0.0, 0.0])
    norm[flat] = 1.0
    h /= norm[:, None]
    v = np.cross(normals_w, h)
    v /= np.linalg.norm(v, axis=1)[:, None]
    return h, v
