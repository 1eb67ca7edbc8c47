"""A world's surfaces as flat arrays for the ray kernel (:mod:`sim._raycast`).

Every visible surface becomes one of four primitives, each with a texture, the map
from its own coordinates to texture coordinates, and how it is lit:

* **vertical quads** (Q): wall faces (both faces and the two end caps of each 10 cm
  slab), the vertical faces of furniture and placed objects, pictures (3 mm proud
  of their wall). A quad runs from ``quad_a`` along the unit ``quad_d`` for
  ``quad_len`` metres and from ``quad_z[0]`` to ``quad_z[1]`` up; ``quad_d`` points
  to the right as one faces the quad, so texture column 0 is on the viewer's left.
  Its outward normal is ``quad_n``.
* **horizontal quads** (F): tops and bottoms of boxes; a rectangle centred at
  ``flat_c`` with axes ``flat_ax`` and its left normal, half sizes ``flat_half``,
  at height ``flat_z``, facing up (``flat_up`` = +1) or down (-1).
* **cylinders** (C): tree trunks; **spheres** (S): tree crowns.
* **planes**: the floor (a raster of material ids at :data:`FLOOR_RES_M`, from the
  floor texture and its regions) and the ceilings (axis-aligned rectangles),
  with lamps set in them (a coarse raster of lamp ids, then an exact rectangle test).

Texture coordinates: ``u = (s - uv[2]) / uv[0]``, ``v = (uv[3] - t) / uv[1]`` where
``s`` runs along the surface to the right and ``t`` upwards (on a quad, ``t = z``), m.
A tiling texture repeats (``uv[0]`` = the width one copy covers); a picture spans its
rectangle once (clamped at its border).

Light: each primitive has a ``*_shade`` factor (its orientation to the light) and an
``*_emit`` factor (> 0: self-lit, such as windows by day and lit lamps; its grey is
the texture times ``emit``); the rest take the light map's value where they are
(:mod:`sim.lightmap`).

Objects placed while a simulation runs (:meth:`sim.simulation.Simulation.add_object`)
join a compiled scene as more quads (:func:`with_objects`); the light map is the
world's, so they cast no shadow.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from sim._atlas import Atlas
from sim._geometry import box_corners
from sim._world_checks import place_picture
from sim.decor import PlacedObject, named
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.lightmap import LightMap, build_light_map
from sim.world import World

FloatArray = npt.NDArray[np.float64]

FLOOR_RES_M = 0.01
"""Cell side of the floor's material raster, m."""
LAMP_RES_M = 0.1
"""Cell side of the ceiling's lamp raster, m."""
PICTURE_PROUD_M = 0.003
"""Distance of a picture in front of its wall's face, m."""
WINDOW_EMIT = 1.25
"""A window's brightness by full daylight, relative to a lit 128-grey surface."""
LAMP_EMIT = 1.9
"""A lit lamp's brightness, relative to a lit 128-grey surface (saturates)."""
_MARGIN_M = 1.0


@dataclass
class Scene:
    """The compiled surfaces of a world (see the module docstring); arrays by primitive."""

    atlas: Atlas
    quad_a: FloatArray
    quad_d: FloatArray
    quad_len: FloatArray
    quad_n: FloatArray
    quad_z: FloatArray
    quad_tex: npt.NDArray[np.int64]
    quad_uv: FloatArray
    quad_shade: FloatArray
    quad_emit: FloatArray
    flat_c: FloatArray
    flat_ax: FloatArray
    flat_half: FloatArray
    flat_z: FloatArray
    flat_up: FloatArray
    flat_tex: npt.NDArray[np.int64]
    flat_uv: FloatArray
    cyl_c: FloatArray
    cyl_r: FloatArray
    cyl_z: FloatArray
    cyl_tex: npt.NDArray[np.int64]
    cyl_uv: FloatArray
    sph_c: FloatArray
    sph_r: FloatArray
    sph_tex: npt.NDArray[np.int64]
    sph_uv: FloatArray
    grid_origin: FloatArray
    floor_map: npt.NDArray[np.uint8]
    floor_tex: npt.NDArray[np.int64]
    floor_uv: FloatArray
    ceil_lo: FloatArray
    ceil_hi: FloatArray
    ceil_z: FloatArray
    ceil_tex: npt.NDArray[np.int64]
    ceil_uv: FloatArray
    lamp_map: npt.NDArray[np.int32]
    lamp_c: FloatArray
    lamp_ax: FloatArray
    lamp_half: FloatArray
    lamp_tex: npt.NDArray[np.int64]
    lamp_emit: FloatArray
    light: LightMap
    sky: FloatArray
    sun_w: FloatArray
    max_height_m: float
    picture_corners_w: FloatArray
    picture_normals_w: FloatArray


class _Builder:
    """Collects primitives, then freezes them into a :class:`Scene`."""

    def __init__(self, world: World, atlas: Atlas, sun_w: FloatArray) -> None:
        self.world, self.atlas, self.sun_w = world, atlas, sun_w
        self.quads: list[tuple] = []
        self.flats: list[tuple] = []

    def uv(self, name: str, extent: tuple[float, float], scale_m: float | None) -> tuple:
        """(su, sv, u0, v0) of texture ``name`` on a surface of ``extent`` (w, h), m."""
        texture = self.atlas.texture(name)
        if texture.tiles:
            su = scale_m or texture.size_m[0]
            return su, su * texture.size_m[1] / texture.size_m[0], 0.0, 0.0
        return extent[0], extent[1], 0.0, extent[1]

    def outdoor(self, xy: tuple[float, float]) -> bool:
        return not any(c.min_corner[0] <= xy[0] <= c.max_corner[0]
                       and c.min_corner[1] <= xy[1] <= c.max_corner[1]
                       for c in self.world.ceilings)

    def shade(self, n: tuple[float, float], mid: tuple[float, float]) -> float:
        """Orientation factor of a vertical surface with outward normal ``n``."""
        if self.outdoor(mid):
            return 0.55 + 0.5 * max(0.0, n[0] * self.sun_w[0] + n[1] * self.sun_w[1])
        return 0.9

    def quad(self, a: FloatArray, d: FloatArray, length: float, z: tuple[float, float],
             name: str, scale_m: float | None, *, emit: float = 0.0,
             v_ref: float | None = None) -> None:
        """A vertical quad from ``a`` along ``d`` (unit, to the viewer's right)."""
        n = (float(d[1]), float(-d[0]))  # right of the viewer is d: the normal is d turned cw
        su, sv, u0, v0 = self.uv(name, (length, z[1] - z[0]), scale_m)
        if not self.atlas.texture(name).tiles:
            v0 = z[1]
        elif v_ref is not None:
            v0 = v_ref
        mid = (float(a[0] + 0.5 * length * d[0]), float(a[1] + 0.5 * length * d[1]))
        self.quads.append((a, d, length, n, z, self.atlas.id_of(name), (su, sv, u0, v0),
                           self.shade(n, mid), emit))

    def box(self, corners: FloatArray, z: tuple[float, float], textures: tuple[str, str, str],
            scale_m: float | None) -> None:
        """A box: four faces (long faces: edges 0 and 2), top, and bottom when raised."""
        top, front, ends = textures
        for k in range(4):
            a, b = corners[k], corners[(k + 1) % 4]
            e = b - a
            length = float(np.hypot(*e))
            self.quad(a, e / length, length, z, front if k % 2 == 0 else ends, scale_m)
        centre = corners.mean(axis=0)
        e0, e1 = corners[1] - corners[0], corners[2] - corners[1]
        half = (float(np.hypot(*e0)) / 2, float(np.hypot(*e1)) / 2)
        ax = e0 / (2 * half[0])
        for zz, up in ((z[1], 1.0), (z[0], -1.0)):
            if up < 0 and z[0] <= 1e-6:
                continue
            su, sv, u0, v0 = self.uv(top, (2 * half[0], 2 * half[1]), scale_m)
            if not self.atlas.texture(top).tiles:
                u0, v0 = -half[0], half[1]
            self.flats.append((centre, ax, half, zz, up, self.atlas.id_of(top), (su, sv, u0, v0)))

    def objects(self, objects: Iterable[PlacedObject]) -> None:
        """Placed objects as boxes, each as it stands (a door turned open)."""
        for obj in objects:
            textures = tuple(named(obj.kind, name, k)
                             for k, name in enumerate((obj.top, obj.texture, obj.sides)))
            z = (obj.elevation_m, obj.elevation_m + obj.height_m)
            self.box(box_corners(*obj.footprint()), z, textures,  # type: ignore[arg-type]
                     obj.scale_m)

    def arrays(self) -> dict[str, npt.NDArray]:
        """The quads and flats collected, as the :class:`Scene`'s ``quad_*`` and ``flat_*``."""
        q = list(zip(*self.quads, strict=True)) if self.quads else [()] * 9
        f = list(zip(*self.flats, strict=True)) if self.flats else [()] * 7
        return {
            "quad_a": np.array(q[0], float).reshape(-1, 2),
            "quad_d": np.array(q[1], float).reshape(-1, 2),
            "quad_len": np.array(q[2], float),
            "quad_n": np.array(q[3], float).reshape(-1, 2),
            "quad_z": np.array(q[4], float).reshape(-1, 2),
            "quad_tex": np.array(q[5], np.int64),
            "quad_uv": np.array(q[6], float).reshape(-1, 4),
            "quad_shade": np.array(q[7], float),
            "quad_emit": np.array(q[8], float),
            "flat_c": np.array(f[0], float).reshape(-1, 2),
            "flat_ax": np.array(f[1], float).reshape(-1, 2),
            "flat_half": np.array(f[2], float).reshape(-1, 2),
            "flat_z": np.array(f[3], float),
            "flat_up": np.array(f[4], float),
            "flat_tex": np.array(f[5], np.int64),
            "flat_uv": np.array(f[6], float).reshape(-1, 4),
        }


def build_scene(world: World, atlas: Atlas) -> Scene:
    """Compile ``world``'s surfaces (see the module docstring).

    Raises:
        ConfigError: a texture the world names is missing from its set.
    """
    sun = math.radians(world.sky.sun_azimuth_deg)
    sun_w = np.array([math.cos(sun), math.sin(sun)])
    b = _Builder(world, atlas, sun_w)
    h = WALL_HALF_THICKNESS_M
    for wall in world.walls:
        start, end = np.asarray(wall.start, float), np.asarray(wall.end, float)
        d = (end - start) / wall.length_m
        nl = np.array([-d[1], d[0]])
        left = named("wall", wall.left or wall.texture)
        right = named("wall", wall.right or wall.texture)
        z = (0.0, wall.height_m)
        b.quad(end + h * nl, -d, wall.length_m, z, left, wall.scale_m)
        b.quad(start - h * nl, d, wall.length_m, z, right, wall.scale_m)
        b.quad(start + h * nl, -nl, 2 * h, z, right, wall.scale_m)
        b.quad(end - h * nl, nl, 2 * h, z, left, wall.scale_m)
    for box, corners in zip(world.furniture, world.furniture_corners(), strict=True):
        textures = tuple(named(box.kind, name, k)
                         for k, name in enumerate((box.top, box.front, box.sides)))
        b.box(corners, (0.0, box.height_m), textures, box.scale_m)  # type: ignore[arg-type]
    b.objects(world.objects)
    corners_w, normals_w = _pictures(world, b)
    trees = _trees(world, atlas, sun_w)
    floor_map, floor_tex, floor_uv, origin = _floor(world, atlas)
    ceilings = _ceilings(world, atlas)
    lamps = _lamps(world, atlas, origin, floor_map.shape)
    heights = [w.height_m for w in world.walls] + [t.trunk_height_m + t.crown_radius_m
                                                   for t in world.trees]
    return Scene(
        atlas=atlas.freeze(),
        **b.arrays(),
        **trees,
        grid_origin=origin,
        floor_map=floor_map,
        floor_tex=floor_tex,
        floor_uv=floor_uv,
        **ceilings,
        **lamps,
        light=build_light_map(world, origin),
        sky=np.array([world.sky.horizon, world.sky.zenith], float) * world.lighting.daylight,
        sun_w=sun_w,
        max_height_m=max(heights),
        picture_corners_w=corners_w,
        picture_normals_w=normals_w,
    )


def with_objects(scene: Scene, world: World, objects: Iterable[PlacedObject]) -> Scene:
    """A copy of ``scene`` (compiled from ``world`` by :func:`build_scene`) with
    ``objects`` added as boxes; ``scene``'s arrays stay as they were, its atlas (shared
    by both) gains the objects' textures.

    Raises:
        ConfigError: a texture an object names is missing from the world's set.
    """
    b = _Builder(world, scene.atlas, scene.sun_w)
    objects = list(objects)
    b.objects(objects)
    scene.atlas.freeze()
    added = {name: np.concatenate([getattr(scene, name), values])
             for name, values in b.arrays().items()}
    tops = [o.elevation_m + o.height_m for o in objects]
    return dataclasses.replace(scene, **added, max_height_m=max([scene.max_height_m, *tops]))


def _pictures(world: World, b: _Builder) -> tuple[FloatArray, FloatArray]:
    """Add the pictures as quads.

    Returns:
        corners: (P, 4, 3) world frame, m, in texture order: top-left, top-right,
            bottom-right, bottom-left.
        normals: (P, 3) unit normals, world frame (horizontal).
    """
    corners, normals = [], []
    for picture in world.pictures:
        place = place_picture(world.walls, picture)
        wall = world.walls[place.wall]
        texture = b.atlas.texture(picture.texture)
        w, hh = picture.size or texture.size_m
        start = np.asarray(wall.start, float)
        d = (np.asarray(wall.end, float) - start) / wall.length_m
        normal = place.side * np.array([-d[1], d[0]])
        right = np.array([-normal[1], normal[0]])
        centre = start + place.along_m * d + (WALL_HALF_THICKNESS_M + PICTURE_PROUD_M) * normal
        a = centre - 0.5 * w * right
        z = (picture.height_m - hh / 2, picture.height_m + hh / 2)
        emit = WINDOW_EMIT * world.lighting.daylight if texture.kind == "window" else 0.0
        b.quad(a, right, w, z, picture.texture, None, emit=emit)
        tl, tr = a, a + w * right
        corners.append([[*tl, z[1]], [*tr, z[1]], [*tr, z[0]], [*tl, z[0]]])
        normals.append([*normal, 0.0])
    return np.array(corners, float).reshape(-1, 4, 3), np.array(normals, float).reshape(-1, 3)


def _trees(world: World, atlas: Atlas, sun_w: FloatArray) -> dict[str, npt.NDArray]:
    """Trunks (cylinders) and crowns (spheres)."""
    bark = [atlas.id_of(named("tree", t.bark, 0)) for t in world.trees]
    leaves = [atlas.id_of(named("tree", t.foliage, 1)) for t in world.trees]

    def size(name_id: list[int], part: int) -> FloatArray:
        out = []
        for t in world.trees:
            tex = atlas.texture(named("tree", (t.bark, t.foliage)[part], part))
            out.append(tex.size_m)
        return np.array(out, float).reshape(-1, 2)

    return {
        "cyl_c": np.array([t.at for t in world.trees], float).reshape(-1, 2),
        "cyl_r": np.array([t.trunk_radius_m for t in world.trees], float),
        "cyl_z": np.array([(0.0, t.trunk_height_m) for t in world.trees], float).reshape(-1, 2),
        "cyl_tex": np.array(bark, np.int64),
        "cyl_uv": size(bark, 0),
        "sph_c": np.array([(*t.at, t.trunk_height_m) for t in world.trees], float).reshape(-1, 3),
        "sph_r": np.array([t.crown_radius_m for t in world.trees], float),
        "sph_tex": np.array(leaves, np.int64),
        "sph_uv": size(leaves, 1),
    }


def _grid(world: World, res: float) -> tuple[FloatArray, tuple[int, int]]:
    (x0, y0), (x1, y1) = world.extent()
    origin = np.array([x0 - _MARGIN_M, y0 - _MARGIN_M])
    shape = (math.ceil((y1 - y0 + 2 * _MARGIN_M) / res), math.ceil((x1 - x0 + 2 * _MARGIN_M) / res))
    return origin, shape


def _floor(world: World, atlas: Atlas) -> tuple:
    """Material raster (rows along y), texture ids and (su, sv) per material, grid origin."""
    origin, shape = _grid(world, FLOOR_RES_M)
    names = [(named("floor", world.floor.texture), world.floor.scale_m)]
    floor_map = np.zeros(shape, np.uint8)
    for region in world.floor.regions:
        names.append((region.texture, region.scale_m))
        pts = ((np.asarray(region.polygon) - origin) / FLOOR_RES_M * 16 - 8).round()
        cv2.fillPoly(floor_map, [pts.astype(np.int32)], len(names) - 1, cv2.LINE_8, 4)
    tex, uv = [], []
    for name, scale in names:
        texture = atlas.texture(name)
        su = scale or texture.size_m[0]
        sv = su * texture.size_m[1] / texture.size_m[0]
        tex.append(atlas.id_of(name))
        uv.append((su, sv))
    return floor_map, np.array(tex, np.int64), np.array(uv, float), origin


def _ceilings(world: World, atlas: Atlas) -> dict[str, npt.NDArray]:
    tex, uv = [], []
    for c in world.ceilings:
        name = named("ceiling", c.texture)
        texture = atlas.texture(name)
        su = c.scale_m or texture.size_m[0]
        tex.append(atlas.id_of(name))
        uv.append((su, su * texture.size_m[1] / texture.size_m[0]))
    return {
        "ceil_lo": np.array([c.min_corner for c in world.ceilings], float).reshape(-1, 2),
        "ceil_hi": np.array([c.max_corner for c in world.ceilings], float).reshape(-1, 2),
        "ceil_z": np.array([c.height_m for c in world.ceilings], float),
        "ceil_tex": np.array(tex, np.int64),
        "ceil_uv": np.array(uv, float).reshape(-1, 2),
    }


def _lamps(world: World, atlas: Atlas, origin: FloatArray,
           floor_shape: tuple[int, ...]) -> dict[str, npt.NDArray]:
    """Lamp rectangles and a coarse raster of lamp id + 1 (0 = none) over the grid."""
    f = FLOOR_RES_M / LAMP_RES_M
    shape = (math.ceil(floor_shape[0] * f), math.ceil(floor_shape[1] * f))
    lamp_map = np.zeros(shape, np.int32)
    centres, axes, halves, tex, emit = [], [], [], [], []
    for i, lamp in enumerate(world.lamps):
        corners = box_corners(lamp.center, lamp.size, lamp.yaw_deg)
        pts = ((corners - origin) / LAMP_RES_M * 16 - 8).round().astype(np.int32)
        cv2.fillConvexPoly(lamp_map, pts, i + 1, cv2.LINE_8, 4)
        cv2.polylines(lamp_map, [pts], True, i + 1, 2, cv2.LINE_8, 4)
        yaw = math.radians(lamp.yaw_deg)
        centres.append(lamp.center)
        axes.append((math.cos(yaw), math.sin(yaw)))
        halves.append((lamp.size[0] / 2, lamp.size[1] / 2))
        tex.append(atlas.id_of(named("lamp", lamp.texture)))
        emit.append(LAMP_EMIT * min(lamp.power, 1.5) if lamp.on else 0.0)
    return {
        "lamp_map": lamp_map,
        "lamp_c": np.array(centres, float).reshape(-1, 2),
        "lamp_ax": np.array(axes, float).reshape(-1, 2),
        "lamp_half": np.array(halves, float).reshape(-1, 2),
        "lamp_tex": np.array(tex, np.int64),
        "lamp_emit": np.array(emit, float),
    }
