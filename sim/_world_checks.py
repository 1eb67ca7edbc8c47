"""The rules a world must satisfy (see :mod:`sim.world`): clearance, decor, texture names.

Kept apart from the dataclasses so that :mod:`sim.world` stays the format. Every
check raises ``ValueError`` naming the entry (``pictures[3]``, ``walls[2].left``) and
the problem; :func:`sim.world.load_world` prefixes the file.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from shared.config import require
from shared.errors import ConfigError
from sim._geometry import (
    point_segment_distances,
    points_in_polygons,
    polygon_edges,
    segment_segment_distance,
)
from sim.decor import PICTURE_REACH_M, Picture, texture_uses
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.texture_library import TextureLibrary

if TYPE_CHECKING:
    from sim.world import Wall, World

CLEARANCE_M = 0.4
"""Least free distance from the start pose and routes to any wall or furniture surface, m."""


@functools.cache
def textures_for(texture_set: str) -> TextureLibrary:
    """The built-in textures, plus those of the manifest ``texture_set`` ("" = none).

    Raises:
        ConfigError: the extra set is bad (one line naming its manifest, entry, problem).
    """
    builtin = TextureLibrary.builtin()
    if not texture_set:
        return builtin
    extra = TextureLibrary.load(Path(texture_set))
    merged = {name: builtin.get(name) for name in builtin.names()}
    merged.update({name: extra.get(name) for name in extra.names()})
    return TextureLibrary(merged, f"{texture_set} + built-in textures")


@dataclass(frozen=True, slots=True)
class PicturePlace:
    """Where a picture sits: on wall ``wall``, face ``side`` (+1 left, -1 right of start->end).

    ``along_m`` is the distance of its centre from the wall's start along the wall.
    """

    wall: int
    side: int
    along_m: float


def place_picture(walls: tuple[Wall, ...], picture: Picture) -> PicturePlace:
    """The wall face nearest ``picture.at`` and the picture's centre on it.

    Raises:
        ValueError: no wall face within :data:`~sim.decor.PICTURE_REACH_M` of ``at``.
    """
    a = np.array([w.start for w in walls], dtype=float)
    b = np.array([w.end for w in walls], dtype=float)
    at = np.asarray(picture.at, dtype=float)
    gaps = point_segment_distances(at[None, :], a, b)[0] - WALL_HALF_THICKNESS_M
    i = int(np.argmin(gaps))
    require(gaps[i] <= PICTURE_REACH_M,
            f"at {picture.at} is {gaps[i]:.2f} m from the nearest wall face; "
            f"need <= {PICTURE_REACH_M} m")
    d = b[i] - a[i]
    length = float(np.hypot(*d))
    along = float(np.dot(at - a[i], d)) / length
    side = 1 if d[0] * (at[1] - a[i][1]) - d[1] * (at[0] - a[i][0]) > 0 else -1
    return PicturePlace(i, side, along)


def check_decor(world: World) -> None:
    """Texture names exist; pictures fit on a wall; lamps are under a ceiling.

    Raises:
        ValueError: naming the entry and the problem.
        ConfigError: the world's extra texture set is bad.
    """
    uses = list(texture_uses(world))
    if uses:
        library = textures_for(world.texture_set)
        known = set(library.names())
        for entry, name in uses:
            if name not in known:
                try:
                    library.get(name)
                except ConfigError as e:
                    raise ValueError(f"{entry}: {e.problem}") from None
    for i, picture in enumerate(world.pictures):
        try:
            place = place_picture(world.walls, picture)
        except ValueError as e:
            raise ValueError(f"pictures[{i}]: {e}") from None
        wall = world.walls[place.wall]
        if picture.size is None:
            size = world.textures().get(picture.texture).size_m
        else:
            size = picture.size
        require(size[0] / 2 <= place.along_m <= wall.length_m - size[0] / 2,
                f"pictures[{i}]: {size[0]} m wide at {place.along_m:.2f} m along walls"
                f"[{place.wall}] does not fit on its {wall.length_m:.2f} m")
        require(size[1] / 2 <= picture.height_m <= wall.height_m - size[1] / 2,
                f"pictures[{i}]: {size[1]} m high centred at {picture.height_m} m does not fit "
                f"on walls[{place.wall}], {wall.height_m} m high")
    for i, lamp in enumerate(world.lamps):
        x, y = lamp.center
        require(any(c.min_corner[0] <= x <= c.max_corner[0] and c.min_corner[1] <= y
                    <= c.max_corner[1] for c in world.ceilings),
                f"lamps[{i}]: no ceiling above {lamp.center}")


@dataclass(frozen=True)
class Obstacles:
    """Walls (with thickness), box edges and tree trunks as one set of segments.

    Boxes are the furniture, then the placed objects as they stand; a trunk is a
    segment of zero length with the trunk's radius.
    """

    world: World
    a: np.ndarray  # (S, 2) segment starts: walls, 4 edges per box, trunks
    b: np.ndarray  # (S, 2) segment ends
    radius: np.ndarray  # (S,) half thickness: walls', 0 for box edges, trunk radius
    corners: np.ndarray  # (F + O, 4, 2) box footprints

    @classmethod
    def of(cls, world: World) -> Obstacles:
        corners = np.concatenate([world.furniture_corners(), world.object_corners()])
        edge_a, edge_b = polygon_edges(corners)
        trunks = np.array([t.at for t in world.trees], dtype=float).reshape(-1, 2)
        walls = np.array([w.start for w in world.walls], dtype=float)
        a = np.concatenate([walls, edge_a, trunks])
        b = np.concatenate([np.array([w.end for w in world.walls], dtype=float), edge_b, trunks])
        radius = np.concatenate([
            np.full(len(world.walls), WALL_HALF_THICKNESS_M), np.zeros(len(edge_a)),
            np.array([t.trunk_radius_m for t in world.trees], dtype=float)])
        return cls(world, a, b, radius, corners)

    def _name(self, segment: int) -> str:
        walls, furniture = self.world.walls, self.world.furniture
        if segment < len(walls):
            return f"wall {segment} ({walls[segment].start} to {walls[segment].end})"
        box = (segment - len(walls)) // 4
        if box < len(furniture):
            return f"furniture {box} at {furniture[box].center}"
        if box < len(furniture) + len(self.world.objects):
            obj = box - len(furniture)
            return f"object {obj} at {self.world.objects[obj].center}"
        tree = segment - len(walls) - 4 * len(self.corners)
        return f"tree {tree} at {self.world.trees[tree].at}"

    def _require_gap(self, what: str, gaps: np.ndarray) -> None:
        i = int(np.argmin(gaps))
        require(
            gaps[i] >= CLEARANCE_M,
            f"{what} is {max(float(gaps[i]), 0.0):.2f} m from {self._name(i)}; "
            f"need >= {CLEARANCE_M} m",
        )

    def check_point(self, what: str, xy: tuple[float, float]) -> None:
        lo, hi = self.world.extent()
        require(
            lo[0] <= xy[0] <= hi[0] and lo[1] <= xy[1] <= hi[1],
            f"{what} {tuple(xy)} is outside the walls' extent {lo}..{hi}",
        )
        point = np.asarray([xy], dtype=float)
        gaps = point_segment_distances(point, self.a, self.b)[0] - self.radius
        inside = points_in_polygons(point, self.corners)[0]
        if inside.any():
            gaps[len(self.world.walls) + 4 * int(np.argmax(inside))] = 0.0
        self._require_gap(f"{what} {tuple(xy)}", gaps)

    def check_leg(self, what: str, p: tuple[float, float], q: tuple[float, float]) -> None:
        gaps = (
            segment_segment_distance(
                np.asarray(p, dtype=float), np.asarray(q, dtype=float), self.a, self.b
            )
            - self.radius
        )
        self._require_gap(what, gaps)

