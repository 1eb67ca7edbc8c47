"""The light on a world's floor plan: lamps, daylight through windows, open sky.

A raster of :data:`LIGHT_RES_M` cells over the floor plan holds the light falling
at table height (0.75 m), relative to standing under one lit office lamp (~1):

* under a ceiling: ``ambient`` plus each lit lamp's ``power * cos^3`` falloff
  (``cos`` = the lamp's height above the cell over the distance: an inverse-square
  law with Lambert's cosine at the receiver, and the lamp's own cosine), plus each
  window's daylight, ``daylight * cos * A / (A + r^2)`` on the side it faces (A its
  area, r the distance);
* under open sky: ``daylight``.

A lamp or window lights a cell only if no wall stands between them on the floor
plan (walls reach the ceiling indoors); the raster is then blurred by one cell so
that shadow edges are soft. Light is the same at every height (no shading of the
upper part of a wall apart from the lower): a simplification.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numba
import numpy as np
import numpy.typing as npt

from sim._world_checks import place_picture
from sim.world import World

LIGHT_RES_M = 0.1
"""Cell side of the light raster, m."""
RECEIVER_HEIGHT_M = 0.75
"""Height at which the light is computed, m."""
_LAMP_GAIN = 0.6
_LAMP_REACH_M = 9.0
_WINDOW_GAIN = 0.9
_MARGIN_M = 1.0


@dataclass(frozen=True)
class LightMap:
    """Light per cell of the floor plan (see the module docstring).

    Attributes:
        values: (H, W) float32, rows along +y, columns along +x.
        origin: (2,) world (x, y) of cell (0, 0)'s corner, m.
        res_m: cell side, m.
    """

    values: npt.NDArray[np.float32]
    origin: npt.NDArray[np.float64]
    res_m: float

    def at(self, xy: npt.ArrayLike) -> npt.NDArray[np.float32]:
        """Light at points (N, 2) (nearest cell; outside the raster: the edge's)."""
        p = (np.asarray(xy, float).reshape(-1, 2) - self.origin) / self.res_m
        h, w = self.values.shape
        col = np.clip(p[:, 0].astype(int), 0, w - 1)
        row = np.clip(p[:, 1].astype(int), 0, h - 1)
        return self.values[row, col]


def build_light_map(world: World, origin: npt.NDArray[np.float64]) -> LightMap:
    """The light raster of ``world`` whose cell (0, 0) starts at ``origin``."""
    _, (x1, y1) = world.extent()
    w = math.ceil((x1 - origin[0] + _MARGIN_M) / LIGHT_RES_M)
    h = math.ceil((y1 - origin[1] + _MARGIN_M) / LIGHT_RES_M)
    xs = origin[0] + (np.arange(w) + 0.5) * LIGHT_RES_M
    ys = origin[1] + (np.arange(h) + 0.5) * LIGHT_RES_M
    roof = np.full((h, w), -1.0)
    for c in sorted(world.ceilings, key=lambda c: -c.height_m):
        inside_x = (xs >= c.min_corner[0]) & (xs <= c.max_corner[0])
        inside_y = (ys >= c.min_corner[1]) & (ys <= c.max_corner[1])
        roof[np.ix_(inside_y, inside_x)] = c.height_m
    light = np.where(roof > 0, world.lighting.ambient, world.lighting.daylight)
    seg_a = np.array([wl.start for wl in world.walls], float)
    seg_b = np.array([wl.end for wl in world.walls], float)
    # Sources: (x, y, kind 0 lamp / 1 window, nx, ny, strength, height above receiver).
    sources = []
    for lamp in world.lamps:
        if lamp.on and lamp.power > 0:
            height = _roof_at(world, lamp.center) - RECEIVER_HEIGHT_M
            sources.append((*lamp.center, 0.0, 0.0, 0.0, lamp.power * _LAMP_GAIN, height))
    for picture in world.pictures:
        texture = world.textures().get(picture.texture)
        if texture.kind != "window" or world.lighting.daylight <= 0:
            continue
        place = place_picture(world.walls, picture)
        wall = world.walls[place.wall]
        d = np.subtract(wall.end, wall.start) / wall.length_m
        n = place.side * np.array([-d[1], d[0]])
        centre = np.asarray(wall.start) + place.along_m * d + 0.08 * n
        width, height = picture.size or texture.size_m
        sources.append((*centre, 1.0, *n, world.lighting.daylight * _WINDOW_GAIN,
                        width * height))
    if sources:
        _add_sources(light, xs, ys, roof > 0, np.array(sources, float), seg_a, seg_b)
    values = cv2.GaussianBlur(light.astype(np.float32), (0, 0), 1.0)
    return LightMap(values, np.asarray(origin, float), LIGHT_RES_M)


def _roof_at(world: World, xy: tuple[float, float]) -> float:
    heights = [c.height_m for c in world.ceilings
               if c.min_corner[0] <= xy[0] <= c.max_corner[0]
               and c.min_corner[1] <= xy[1] <= c.max_corner[1]]
    return min(heights) if heights else RECEIVER_HEIGHT_M + 2.0


@numba.njit(cache=True)
def _blocked(px: float, py: float, qx: float, qy: float,
             seg_a: npt.NDArray[np.float64], seg_b: npt.NDArray[np.float64]) -> bool:
    """Whether segment p-q properly crosses any wall centre line."""
    for k in range(seg_a.shape[0]):
        ax, ay, bx, by = seg_a[k, 0], seg_a[k, 1], seg_b[k, 0], seg_b[k, 1]
        d1 = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        d2 = (bx - ax) * (qy - ay) - (by - ay) * (qx - ax)
        if d1 * d2 >= 0:
            continue
        d3 = (qx - px) * (ay - py) - (qy - py) * (ax - px)
        d4 = (qx - px) * (by - py) - (qy - py) * (bx - px)
        if d3 * d4 < 0:
            return True
    return False


@numba.njit(cache=True)
def _add_sources(light: npt.NDArray[np.float64], xs: npt.NDArray[np.float64],
                 ys: npt.NDArray[np.float64], indoor: npt.NDArray[np.bool_],
                 sources: npt.NDArray[np.float64], seg_a: npt.NDArray[np.float64],
                 seg_b: npt.NDArray[np.float64]) -> None:
    """Add each source's light to the indoor cells it reaches (see the module docstring)."""
    res = xs[1] - xs[0] if xs.shape[0] > 1 else 1.0
    reach = int(_LAMP_REACH_M / res)
    for s in range(sources.shape[0]):
        sx, sy, kind, nx, ny, strength, extra = sources[s]
        ci = int((sx - xs[0]) / res + 0.5)
        ri = int((sy - ys[0]) / res + 0.5)
        for r in range(max(ri - reach, 0), min(ri + reach + 1, ys.shape[0])):
            for c in range(max(ci - reach, 0), min(ci + reach + 1, xs.shape[0])):
                if not indoor[r, c]:
                    continue
                dx, dy = xs[c] - sx, ys[r] - sy
                r2 = dx * dx + dy * dy
                if kind == 0.0:
                    cos = extra / math.sqrt(r2 + extra * extra)
                    e = strength * cos * cos * cos
                else:
                    dist = math.sqrt(r2) + 1e-9
                    cos = (dx * nx + dy * ny) / dist
                    if cos <= 0.0:
                        continue
                    e = strength * cos * extra / (extra + r2)
                if e < 0.004 or _blocked(sx, sy, xs[c], ys[r], seg_a, seg_b):
                    continue
                light[r, c] += e
