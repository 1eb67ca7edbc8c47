"""Where a moved object may stand (rule 2 of :mod:`sim.scene_change`).

An object moves by at most :data:`MOVE_MAX_M` and turns by at most
:data:`TURN_MAX_DEG`, to a place where its whole footprint lies in free space
reachable from the start, clear of walls, furniture, the other objects and tree
trunks by :data:`MOVE_GAP_M`, at least :data:`KEEP_CLEAR_M` from each point the
caller keeps clear, and where the changed world still satisfies every rule of
:mod:`sim.world` (its routes keep their clearance and stay reachable). A draw that
breaks one of these is redrawn, up to :data:`MOVE_TRIES` times.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import numpy.typing as npt

from sim._geometry import box_corners, point_segment_distances, points_in_polygons, polygon_edges
from sim._world_checks import Obstacles
from sim.decor import PlacedObject
from sim.free_space import FreeSpaceMap
from sim.world import World

MOVE_MAX_M = 1.0
"""Largest displacement of a moved object's centre, m."""
TURN_MAX_DEG = 45.0
"""Largest rotation of a moved object, degrees."""
MOVE_GAP_M = 0.05
"""Least free gap between a moved object and walls, furniture, other objects, trunks, m."""
KEEP_CLEAR_M = 0.8
"""Least distance from a moved object's footprint to each point kept clear, m (a robot's
half-diagonal, 0.4 m, and room to turn)."""
MOVE_TRIES = 40
"""Draws per object before it is left where it was."""
_OUTLINE_STEP_M = 0.05  # the footprint's outline is checked at points this far apart


def placed_elsewhere(world: World, index: int, rng: np.random.Generator,
                     keep_clear_xy: npt.NDArray[np.float64]) -> World | None:
    """``world`` with ``world.objects[index]`` at a new place (module rules), or None when
    :data:`MOVE_TRIES` draws found none.

    Args:
        world: the world.
        index: the object to move.
        rng: draws the displacement and the turn.
        keep_clear_xy: (K, 2) points kept :data:`KEEP_CLEAR_M` clear, m.
    """
    objects = world.objects
    obj = objects[index]
    without = replace(world, objects=objects[:index] + objects[index + 1:])
    free = FreeSpaceMap.from_world(without)
    obstacles = Obstacles.of(without)
    trunks = np.array([t.at for t in world.trees], dtype=float).reshape(-1, 2)
    for _ in range(MOVE_TRIES):
        radius, bearing = MOVE_MAX_M * math.sqrt(rng.uniform()), rng.uniform(0.0, 2 * math.pi)
        candidate = replace(
            obj,
            center=(obj.center[0] + radius * math.cos(bearing),
                    obj.center[1] + radius * math.sin(bearing)),
            yaw_deg=obj.yaw_deg + rng.uniform(-TURN_MAX_DEG, TURN_MAX_DEG),
        )
        if not _fits(candidate, free, obstacles, trunks, keep_clear_xy):
            continue
        try:
            return replace(world, objects=(*objects[:index], candidate, *objects[index + 1:]))
        except ValueError:  # too near a route or the start, or cuts a route off
            continue
    return None


def _fits(obj: PlacedObject, free: FreeSpaceMap, obstacles: Obstacles,
          trunks: npt.NDArray[np.float64], keep_clear_xy: npt.NDArray[np.float64]) -> bool:
    """Whether ``obj`` stands in reachable free space, ``MOVE_GAP_M`` clear of the
    obstacles (the world without it) and ``KEEP_CLEAR_M`` from the kept points."""
    corners = box_corners(*obj.footprint())
    edge_a, edge_b = polygon_edges(corners[None])
    count = max(2, math.ceil(max(obj.size) / _OUTLINE_STEP_M))
    steps = np.linspace(0.0, 1.0, count)[:, None, None]
    outline = (edge_a[None] + steps * (edge_b - edge_a)[None]).reshape(-1, 2)
    centre = np.asarray([obj.footprint()[0]], dtype=float)
    if not free.is_reachable(np.vstack([outline, centre])).all():
        return False
    gaps = point_segment_distances(outline, obstacles.a, obstacles.b) - obstacles.radius
    if gaps.min() < MOVE_GAP_M:
        return False
    inside = [points_in_polygons(outline, obstacles.corners),
              points_in_polygons(obstacles.corners.reshape(-1, 2), corners[None]),
              points_in_polygons(trunks, corners[None])]
    if any(hit.any() for hit in inside):
        return False
    if len(keep_clear_xy) == 0:
        return True
    near = point_segment_distances(keep_clear_xy, edge_a, edge_b).min()
    return bool(near >= KEEP_CLEAR_M and not points_in_polygons(keep_clear_xy, corners[None]).any())
