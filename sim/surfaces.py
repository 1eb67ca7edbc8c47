"""Shaded scene surfaces behind the landmarks: walls, furniture, floor, ceilings and sky.

The renderer paints landmark patches and people over this image. It is computed
on a grid coarser than the image (``downsample`` in each axis) by 2D ray casting
on the floor plan, one ray per azimuth bin (all vectorised):

1. **Construction.** The centres of the coarse grid's cells are lifted with the
   camera model and turned into the robot (base) frame with the camera mount.
   Each keeps its azimuth bin (relative to the robot's heading), its offset
   ``delta`` from the bin's central azimuth, and the slope ``t = tan(elevation)``
   of its ray. Cells outside the lens's image circle (beyond a small margin kept
   for the blur) are not computed.
2. **Rays.** Per frame, one ray per bin leaves the camera's floor-plan position.
   Each wall centre line and each furniture footprint edge facing the camera
   spans the bins between its ends' azimuths; only those (ray, segment) pairs
   are formed, and each pair's distance follows from Cramer's rule on
   ``o + d r = a + s (b - a)``. A wall surface is its slab's face,
   :data:`~sim.free_space.WALL_HALF_THICKNESS_M` in front of the centre line.
3. **Envelope.** Along a ray, a surface of height ``H`` at distance ``d`` is seen
   by the rays of slope up to ``T = (H - h) / d`` (``h``: camera height) that pass
   over everything nearer. The visible surfaces are the nearest hit, then the
   nearest hit behind it with a larger ``T``, and so on (:data:`_LEVELS` of them;
   lower ones behind are hidden).
4. **Within a bin** a cell's ray meets the plane of its bin's surface at
   ``1 / d(alpha + delta) = (n . r cos delta + n . r_perp sin delta) / p`` (``n``,
   ``p``: the plane's normal and distance), which is ``1 / d + g sin delta`` to
   within 4e-5 for half-degree bins, ``g = -(r . e) / (r x e) / d``. So floor and
   wall-top edges follow the true geometry instead of stepping from bin to bin.
5. **Cells.** A cell of slope ``t`` sees the first envelope surface with
   ``T >= t`` unless its ray meets the floor first (``t < -h / d``) or the plane
   of a :class:`~sim.world.Ceiling` under the ceiling's rectangle first (the ray
   reaches the ceiling's height ``C`` at ``r = (C - h) / t``, inside the
   rectangle and before the surface). Above every surface, with no ceiling in
   the way, it sees the sky.
6. **Shade** (``b``: the world's brightness): walls ``b (0.7 + 0.3 cos i)``
   and furniture ``b (0.3 + 0.15 cos i)`` (``i``: angle between the ray and the
   surface normal, a Lambert-like term), floor ``0.6 b``, ceilings
   ``min(1.4 b, 235)``, sky ``min(1.6 b, 250)``; every surface but the sky dims
   mildly with distance ``r``, by ``1 / (1 + r / 40 m)``.
7. **Soft edges.** A Gaussian blur on the coarse grid, then bilinear upsampling
   to the image size: boundaries between surfaces spread over about fifteen
   pixels, which hides the coarse cells' staircase and keeps the Harris response
   of the surfaces far below that of the landmark patches' sharp corners
   (blurring the coarse grid costs a sixteenth of blurring the image, for the
   same softness).

Limits: vertical edges (wall ends, furniture corners) and the ends of ceilings
are placed to the nearest bin (1 degree by default); people do not appear here
(the renderer draws them); overlapping ceilings are tested lowest last, so the
lowest wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.errors import check_shape
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.world import World

FloatArray = npt.NDArray[np.float64]
Float32Array = npt.NDArray[np.float32]

_LEVELS = 3
"""Visible surfaces kept per ray (a desk, a shelf behind it, the wall behind both)."""
_FALLOFF_M = 40.0
"""Distance at which a surface's shade has dimmed to half, m."""
_GRAZING_COS = 0.05
"""Least cosine of incidence used to offset a wall's face from its centre line."""
_MAX_TAN = 1.0 / _GRAZING_COS
"""Largest tangent of incidence used to follow a surface within a bin (about 87 degrees)."""
_MARGIN_CELLS = 2
"""Coarse cells computed beyond the image circle, so the blur does not darken its rim."""


@dataclass(frozen=True, slots=True)
class _Envelope:
    """The visible surfaces along every ray, as flattened (B, levels + 1) float32 tables.

    Entry ``bin * (levels + 1) + k`` is the k-th visible surface of the bin's ray,
    near to far; past the last surface an entry stands for open space (top +inf,
    inverse distance 0, the sky's grey). Rates are derivatives with respect to
    ``sin delta``, the sine of a cell's azimuth offset from the bin's centre.
    """

    top: Float32Array
    """Slope ``(H - h) / d`` of the surface's top edge."""
    top_rate: Float32Array
    """Its rate, ``(H - h) g``."""
    inv_dist: Float32Array
    """``1 / d``, 1/m."""
    inv_dist_rate: Float32Array
    """Its rate ``g``, 1/m."""
    grey: Float32Array
    """Shade of the surface (the sky's for open space)."""
    levels: int
    """Levels holding a surface in some bin (the rest are open space everywhere)."""


class SurfaceShader:
    """Shades the world's surfaces as the fisheye camera sees them from a pose.

    Args:
        world: walls, furniture, ceilings and lighting.
        camera: the lens.
        R_base_cam: (3, 3) rotation taking camera-frame vectors into the robot
            base frame (x forward, y left, z up), as
            :func:`shared.camera_mount.rotation_base_cam` gives it.
        camera_height_m: height of the optical centre above the floor, m.
        downsample: the coarse grid is this many times smaller than the image in
            each axis.
        azimuth_bins: rays cast per frame (azimuth resolution 360 / bins degrees).
        blur_sigma_cells: std of the Gaussian blur on the coarse grid, cells (0 = none).

    Raises:
        ShapeError: ``R_base_cam`` is not (3, 3).
        ValueError: a camera height, downsample, bin count or blur out of range.
    """

    def __init__(
        self,
        world: World,
        camera: CameraModel,
        R_base_cam: FloatArray,
        camera_height_m: float,
        *,
        downsample: int = 4,
        azimuth_bins: int = 360,
        blur_sigma_cells: float = 1.2,
    ) -> None:
        check_shape("R_base_cam", np.shape(R_base_cam), (3, 3))
        height, blur = camera_height_m, blur_sigma_cells
        _require(0 < height < math.inf, "camera_height_m", "finite, > 0", height)
        _require(downsample >= 1, "downsample", ">= 1", downsample)
        _require(azimuth_bins >= 8, "azimuth_bins", ">= 8", azimuth_bins)
        _require(0 <= blur < math.inf, "blur_sigma_cells", "finite, >= 0", blur)
        self.image_size = (camera.width, camera.height)
        self._h = float(camera_height_m)
        self._blur = float(blur_sigma_cells)
        self._bins = int(azimuth_bins)
        # Unit ray directions at the bins' central azimuths, relative to the robot heading.
        centres = (np.arange(self._bins) + 0.5) * (2.0 * math.pi / self._bins) - math.pi
        self._bin_dirs = np.column_stack([np.cos(centres), np.sin(centres)])
        self._scene_arrays(world)
        self._cell_rays(camera, np.asarray(R_base_cam, dtype=np.float64), int(downsample), centres)

    # -- construction -----------------------------------------------------------------

    def _scene_arrays(self, world: World) -> None:
        """Segments (walls, then furniture edges), their heights, ceilings and fixed shades."""
        corners = world.furniture_corners()  # (F, 4, 2) counter-clockwise
        walls = self._walls = len(world.walls)
        starts = [np.array([w.start for w in world.walls]), corners.reshape(-1, 2)]
        ends = [np.array([w.end for w in world.walls]), np.roll(corners, -1, axis=1).reshape(-1, 2)]
        self._seg_a = np.concatenate(starts).astype(np.float64)
        self._seg_e = np.concatenate(ends).astype(np.float64) - self._seg_a
        heights = [
            [w.height_m for w in world.walls],
            np.repeat([f.height_m for f in world.furniture], 4),
        ]
        # Heights of the tops above the camera, m.
        self._seg_rise = (np.concatenate(heights) - self._h).astype(np.float32)
        self._seg_inv_len = (1.0 / np.hypot(self._seg_e[:, 0], self._seg_e[:, 1])).astype(
            np.float32
        )
        # Counter-clockwise footprints: an edge's outward normal is its direction turned
        # clockwise, and the edge faces a point p when normal . p > normal . a.
        self._edge_normal = np.column_stack([self._seg_e[walls:, 1], -self._seg_e[walls:, 0]])
        self._edge_offset = np.einsum("ij,ij->i", self._edge_normal, self._seg_a[walls:])
        lowest_last = sorted(world.ceilings, key=lambda c: -c.height_m)
        self._ceil_lo = np.array([c.min_corner for c in lowest_last]).reshape(-1, 2)
        self._ceil_hi = np.array([c.max_corner for c in lowest_last]).reshape(-1, 2)
        self._ceil_rise = np.array([c.height_m - self._h for c in lowest_last])
        b = world.lighting.brightness
        is_wall = np.arange(self._seg_a.shape[0]) < walls
        # Shade = tone[0] + tone[1] cos(incidence), before the distance falloff.
        self._seg_tone = np.where(is_wall, [[0.7 * b], [0.3 * b]], [[0.3 * b], [0.15 * b]])
        self._seg_half_thickness = np.where(is_wall, WALL_HALF_THICKNESS_M, 0.0)
        self._floor_grey = 0.6 * b
        self._ceiling_grey = min(1.4 * b, 235.0)
        self._sky_grey = min(1.6 * b, 250.0)

    def _cell_rays(
        self, camera: CameraModel, R_base_cam: FloatArray, downsample: int, centres: FloatArray
    ) -> None:
        """Per computed coarse cell: bin, azimuth offset, slope, fixed floor and ceiling shades."""
        w, h = self.image_size
        gw, gh = math.ceil(w / downsample), math.ceil(h / downsample)
        self._grid_shape = (gh, gw)
        # cv2.resize (INTER_LINEAR) puts cell i's centre at image x = (i + 0.5) w / gw - 0.5.
        gu, gv = np.meshgrid(
            (np.arange(gw) + 0.5) * w / gw - 0.5, (np.arange(gh) + 0.5) * h / gh - 0.5
        )
        bearings_c, valid = camera.lift(np.column_stack([gu.ravel(), gv.ravel()]))
        kernel = np.ones((2 * _MARGIN_CELLS + 1, 2 * _MARGIN_CELLS + 1), np.uint8)
        near = cv2.dilate(valid.reshape(gh, gw).astype(np.uint8), kernel).ravel() > 0
        cells = np.flatnonzero(near & np.isfinite(bearings_c).all(axis=1))
        v = bearings_c[cells] @ R_base_cam.T  # base frame
        azimuth = np.arctan2(v[:, 1], v[:, 0])
        bins = np.floor((azimuth + math.pi) * (self._bins / (2.0 * math.pi))).astype(np.intp)
        bins %= self._bins
        slope = v[:, 2] / np.maximum(np.hypot(v[:, 0], v[:, 1]), 1e-9)
        self._cells = cells
        self._bin = bins
        self._row = bins * (_LEVELS + 1)  # the bin's first entry in the envelope tables
        self._rows = [self._row + k for k in range(_LEVELS)]
        self._sin_offset = np.sin(azimuth - centres[bins]).astype(np.float32)
        self._slope = slope.astype(np.float32)
        with np.errstate(divide="ignore"):
            floor_r = np.where(slope < 0, -self._h / slope, 0.0)
            ceil_r = np.where(slope > 0, self._ceil_rise[:, None] / slope, 0.0)
        self._floor_px = (self._floor_grey * _falloff(floor_r)).astype(np.float32)
        self._ceiling_px = (self._ceiling_grey * _falloff(ceil_r)).astype(np.float32)

    # -- per frame --------------------------------------------------------------------

    def shade(self, camera_xy_w: npt.ArrayLike, yaw_rad: float) -> npt.NDArray[np.uint8]:
        """The shaded surfaces seen from a pose.

        Args:
            camera_xy_w: (2,) floor-plan position of the optical centre, world frame, m.
            yaw_rad: the robot's heading, counter-clockwise from world +x, rad.

        Returns:
            (H, W) uint8 grey image, 0 far outside the lens's image circle.
        """
        o = np.asarray(camera_xy_w, dtype=np.float64).reshape(2)
        c, s = math.cos(yaw_rad), math.sin(yaw_rad)
        rays = self._bin_dirs @ np.array([[c, s], [-s, c]])  # (B, 2) world frame
        env = self._cast(o, yaw_rad, rays)
        ceil_lo, ceil_hi = self._ceiling_slopes(o, rays)

        t, sin_offset, row = self._slope, self._sin_offset, self._row
        # The first visible surface whose top edge the cell's ray does not pass over.
        entry = row.copy()
        for k in range(env.levels):
            at = self._rows[k]
            entry += t > env.top.take(at) + env.top_rate.take(at) * sin_offset
        inv_dist = env.inv_dist.take(entry) + env.inv_dist_rate.take(entry) * sin_offset
        grey = env.grey.take(entry)
        grey = np.where(t < -self._h * inv_dist, self._floor_px, grey)
        for j, rise in enumerate(self._ceil_rise):
            # Under the rectangle where the ray reaches the ceiling's height, before the surface.
            under = (t >= ceil_lo[j].take(self._bin)) & (t <= ceil_hi[j].take(self._bin))
            grey = np.where(under & (t > rise * inv_dist), self._ceiling_px[j], grey)

        grid = np.zeros(self._grid_shape, dtype=np.float32)
        grid.ravel()[self._cells] = grey
        if self._blur > 0:
            grid = cv2.GaussianBlur(grid, (0, 0), self._blur)
        return cv2.resize(
            cv2.convertScaleAbs(grid), self.image_size, interpolation=cv2.INTER_LINEAR
        )

    def _cast(self, o: FloatArray, yaw_rad: float, rays: FloatArray) -> _Envelope:
        """The visible surfaces along each ray (steps 2 and 3 of the module docstring).

        Only the (ray, segment) pairs that meet are formed: a segment spans the
        bins whose central azimuths lie between its ends' azimuths, about a
        thousand pairs in the lab against rays x segments = 30 000.

        Args:
            o: (2,) ray origin, world frame, m.
            yaw_rad: the robot's heading, rad.
            rays: (B, 2) unit directions of the bins' rays, world frame.
        """
        walls = self._walls
        facing = walls + np.flatnonzero(self._edge_normal @ o > self._edge_offset)
        keep = np.concatenate([np.arange(walls), facing])
        q = self._seg_a[keep] - o  # (S, 2) segment starts from the camera
        e = self._seg_e[keep]
        end = q + e
        az_start = np.arctan2(q[:, 1], q[:, 0]) - yaw_rad
        turn = (np.arctan2(end[:, 1], end[:, 0]) - yaw_rad - az_start + math.pi) % (2 * math.pi)
        turn -= math.pi  # signed angle the segment subtends, |turn| < pi
        first = np.where(turn > 0, az_start, az_start + turn)
        # Bin k's central azimuth is -pi + (k + 1/2) w: the bins within [first, first + |turn|].
        u = (first + math.pi) * (self._bins / (2.0 * math.pi)) - 0.5
        k0 = np.ceil(u).astype(np.intp)
        count = np.maximum(np.floor(u + np.abs(turn) * (self._bins / (2.0 * math.pi))) - k0 + 1, 0)
        count = count.astype(np.intp)
        pair_seg = np.repeat(np.arange(keep.shape[0]), count)
        offset = np.arange(pair_seg.shape[0]) - np.repeat(np.cumsum(count) - count, count)
        pair_bin = (np.repeat(k0, count) + offset) % self._bins

        # o + d r = a + s e  =>  d = (q x e) / (r x e)  (s is in [0, 1] by construction).
        r = rays[pair_bin]
        ep = e[pair_seg]
        with np.errstate(divide="ignore", invalid="ignore"):
            d = (q[:, 0] * e[:, 1] - q[:, 1] * e[:, 0])[pair_seg] / (
                r[:, 0] * ep[:, 1] - r[:, 1] * ep[:, 0]
            )
            # Along each ray, near to far (distances < 1e6 m; a ray along its segment,
            # without d > 0, last).
            key = np.where(d > 0.0, pair_bin * 1.0e6 + d, np.inf)
        order = np.argsort(key)[: np.count_nonzero(key < np.inf)]
        seg, pair_bin, d = keep[pair_seg[order]], pair_bin[order], d[order]
        # A hit is visible when its top is seen higher than every nearer hit's: a running
        # maximum within each bin (bins apart by more than any clipped slope).
        top_key = pair_bin * 1.0e5 + np.clip(self._seg_rise[seg] / d, -1.0e4, 1.0e4)
        visible = np.empty(top_key.shape, dtype=bool)
        visible[:1] = True
        visible[1:] = top_key[1:] > np.maximum.accumulate(top_key)[:-1]
        vis = np.flatnonzero(visible)
        level = np.arange(vis.shape[0]) - np.searchsorted(pair_bin[vis], pair_bin[vis])
        kept = level < _LEVELS
        vis = vis[kept]
        return self._envelope(rays, pair_bin[vis], level[kept], seg[vis], d[vis])

    def _envelope(
        self,
        rays: FloatArray,
        bins: npt.NDArray[np.intp],
        level: npt.NDArray[np.intp],
        seg: npt.NDArray[np.intp],
        centre_dist: FloatArray,
    ) -> _Envelope:
        """The envelope tables from the visible hits (V,).

        Args:
            rays: (B, 2) unit directions of the bins' rays, world frame.
            bins, level: (V,) where each hit goes in the tables.
            seg: (V,) the segment hit.
            centre_dist: (V,) distance to the segment's centre line, m.
        """
        r = rays[bins]
        e = self._seg_e[seg]
        r_cross_e = r[:, 0] * e[:, 1] - r[:, 1] * e[:, 0]
        cos_i = np.minimum(np.abs(r_cross_e) * self._seg_inv_len[seg], 1.0)
        # A wall's face is its slab's, half a thickness in front of the centre line.
        offset = self._seg_half_thickness[seg] / np.maximum(cos_i, _GRAZING_COS)
        face = np.maximum(centre_dist - offset, 1e-3)
        inv_face = 1.0 / face
        # g of step 4, with the tangent of the incidence kept to that of _GRAZING_COS.
        tan_i = np.clip(-(r[:, 0] * e[:, 0] + r[:, 1] * e[:, 1]) / r_cross_e, -_MAX_TAN, _MAX_TAN)
        rate = tan_i * inv_face
        rise = self._seg_rise[seg]
        grey = (self._seg_tone[0, seg] + self._seg_tone[1, seg] * cos_i) * _falloff(face)
        # Rows: top, top rate, inverse distance, its rate, grey; open space past the last hit.
        tables = np.repeat(
            np.array([np.inf, 0.0, 0.0, 0.0, self._sky_grey], dtype=np.float32),
            rays.shape[0] * (_LEVELS + 1),
        ).reshape(5, -1)
        tables[:, bins * (_LEVELS + 1) + level] = (
            rise * inv_face,
            rise * rate,
            inv_face,
            rate,
            grey,
        )
        return _Envelope(*tables, levels=int(level.max(initial=-1)) + 1)

    def _ceiling_slopes(self, o: FloatArray, rays: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Per ceiling and ray, the slopes of the rays reaching its height under its rectangle.

        The ray ``o + r s`` is under the rectangle for ``s`` in ``[s_in, s_out]``
        (slab method); it reaches height ``C`` at ``s = (C - h) / t``.

        Returns:
            lo, hi: (C, B) float32 slope bounds (lo = +inf where the ray never
            passes under the rectangle).
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_x, inv_y = 1.0 / rays[:, 0], 1.0 / rays[:, 1]  # (B,)
            x0 = (self._ceil_lo[:, 0, None] - o[0]) * inv_x  # (C, B)
            x1 = (self._ceil_hi[:, 0, None] - o[0]) * inv_x
            y0 = (self._ceil_lo[:, 1, None] - o[1]) * inv_y
            y1 = (self._ceil_hi[:, 1, None] - o[1]) * inv_y
            s_in = np.maximum(np.maximum(np.minimum(x0, x1), np.minimum(y0, y1)), 0.0)
            s_out = np.minimum(np.maximum(x0, x1), np.maximum(y0, y1))
            rise = self._ceil_rise[:, None]
            lo = np.where(s_out > s_in, rise / s_out, np.inf)
            hi = np.where(s_out > s_in, rise / s_in, -np.inf)
        return lo.astype(np.float32), hi.astype(np.float32)


def _require(ok: bool, name: str, rule: str, value: float) -> None:
    """Raise ``ValueError`` naming the argument unless ``ok``."""
    if not ok:
        raise ValueError(f"SurfaceShader {name}: must be {rule}, got {value}")


def _falloff(distance_m: npt.ArrayLike) -> FloatArray:
    """Mild dimming with distance: 1 at the camera, 1/2 at :data:`_FALLOFF_M`."""
    return 1.0 / (1.0 + np.asarray(distance_m) / _FALLOFF_M)
