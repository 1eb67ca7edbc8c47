"""What changed between the day a route was taught and the day it is repeated.

A real building is never the same twice: the lights are on or off, the sun has
moved, chairs and boxes stand elsewhere, a door is open, people walk about. Each
change here is a scenario option of the repeat (``vmnav demo``, ``vmnav bench
follow``) and a pure function of the world, seeded by the caller's generator.

Rules:

1. **Pure.** :func:`change_world` returns a new :class:`~sim.world.World`
   (``dataclasses.replace``), so the changed world is checked by the same rules
   as a world file: its start and routes keep :data:`~sim.world.CLEARANCE_M`
   from every wall and object, every waypoint stays reachable.
2. **Moved objects never block the repeat.** An object moves by at most
   :data:`MOVE_MAX_M` and turns by at most :data:`TURN_MAX_DEG`, to a place where
   its whole footprint lies in free space reachable from the start (clear of
   walls and of the other objects by :data:`MOVE_GAP_M`), away from the points the
   caller keeps clear (the repeat's start) by :data:`KEEP_CLEAR_M`, and where the
   changed world still validates. A draw that breaks one of these is redrawn, up
   to :data:`MOVE_TRIES` times; an object with no such place stays where it was
   (:class:`ChangedWorld` counts it).
3. **Light.** A steady change (``LightingChange.scale``) changes the world's
   lighting; a step during the repeat is a gain of the whole scene's light from a
   given time on (:meth:`LightingChange.gain_at`), applied to the rendered scene
   before the camera sees it, so the camera's exposure control has to follow it.
4. **Movable objects.** Until the textured world format flags movable objects,
   the world's furniture boxes are the objects that move.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from shared.config import require
from sim._geometry import box_corners, point_segment_distances, points_in_polygons, polygon_edges
from sim.free_space import WALL_HALF_THICKNESS_M, FreeSpaceMap
from sim.world import Box, World

MOVE_MAX_M = 1.0
"""Largest displacement of a moved object's centre, m."""
TURN_MAX_DEG = 45.0
"""Largest rotation of a moved object, degrees."""
MOVE_GAP_M = 0.05
"""Least free gap between a moved object and walls or other objects, m."""
KEEP_CLEAR_M = 0.8
"""Least distance from a moved object's footprint to each point kept clear, m (a robot's
half-diagonal, 0.4 m, and room to turn)."""
MOVE_TRIES = 40
"""Draws per object before it is left where it was."""


@dataclass(frozen=True, slots=True)
class LightingChange:
    """How the light differs from the teach.

    Attributes:
        scale: the whole scene's light, relative to the teach (1 = unchanged; 0.5 = half
            as bright), for the whole repeat; > 0.
        step_factor: the scene's light is further multiplied by this from ``step_at_s``
            on (1 = no step; 0.4 = someone switched most lights off); > 0.
        step_at_s: time of the step, s since the repeat's simulation started; >= 0.
    """

    scale: float = 1.0
    step_factor: float = 1.0
    step_at_s: float = 0.0

    def __post_init__(self) -> None:
        require(math.isfinite(self.scale) and self.scale > 0,
                f"scale must be > 0, got {self.scale}")
        require(math.isfinite(self.step_factor) and self.step_factor > 0,
                f"step factor must be > 0, got {self.step_factor}")
        require(math.isfinite(self.step_at_s) and self.step_at_s >= 0,
                f"step time must be >= 0 s, got {self.step_at_s}")

    def gain_at(self, t_ns: int) -> float:
        """The step's gain on the scene's light at simulation time ``t_ns``: 1 before
        ``step_at_s``, ``step_factor`` from then on (the steady ``scale`` is in the world)."""
        return self.step_factor if t_ns >= round(self.step_at_s * 1e9) else 1.0

    @property
    def has_step(self) -> bool:
        """Whether the light changes during the repeat."""
        return self.step_factor != 1.0


@dataclass(frozen=True, slots=True)
class SceneChange:
    """Everything that differs between teach and repeat, except the people
    (``SimConfig.people``: nobody walks about while a route is taught).

    Attributes:
        lighting: the light.
        moved_fraction: share of the movable objects moved, in [0, 1];
            ``round(fraction * count)`` objects move.
    """

    lighting: LightingChange = field(default_factory=LightingChange)
    moved_fraction: float = 0.0

    def __post_init__(self) -> None:
        require(0.0 <= self.moved_fraction <= 1.0,
                f"moved fraction must be in [0, 1], got {self.moved_fraction}")

    @property
    def is_none(self) -> bool:
        """Whether nothing changes."""
        return self == SceneChange()


@dataclass(frozen=True, slots=True)
class ChangedWorld:
    """The world after a change, and what moved.

    Attributes:
        world: the changed world (it satisfies every rule of :mod:`sim.world`).
        change: the change applied.
        moved: indices of the objects moved, in ``world.furniture``.
        stuck: indices of the objects drawn to move that found no place (rule 2).
    """

    world: World
    change: SceneChange
    moved: tuple[int, ...] = ()
    stuck: tuple[int, ...] = ()


def change_world(world: World, change: SceneChange, rng: np.random.Generator,
                 keep_clear_xy: npt.NDArray[np.float64] | None = None) -> ChangedWorld:
    """Apply ``change`` to ``world`` (see the module's rules).

    Args:
        world: the world as it was taught.
        change: what changed.
        rng: the only source of randomness (which objects move, and where).
        keep_clear_xy: (K, 2) points on the floor plan no moved object may come
            within :data:`KEEP_CLEAR_M` of (the repeat's start), m; None: none.

    Raises:
        ValueError: the steady light change takes the world's brightness out of its
            range, or objects should move in a world without movable objects.
    """
    world = relit_world(world, change.lighting.scale)
    keep = np.empty((0, 2)) if keep_clear_xy is None else np.asarray(keep_clear_xy, float)
    world, moved, stuck = move_objects(world, change.moved_fraction, rng, keep.reshape(-1, 2))
    return ChangedWorld(world, change, moved, stuck)


def relit_world(world: World, scale: float) -> World:
    """``world`` with its light multiplied by ``scale``.

    Raises:
        ValueError: the resulting brightness leaves the world's range (0, 255).
    """
    if scale == 1.0:
        return world
    brightness = world.lighting.brightness * scale
    require(0.0 < brightness < 255.0,
            f"light scale {scale} makes the brightness {brightness:.0f} of world "
            f"'{world.name}' leave (0, 255)")
    return replace(world, lighting=replace(world.lighting, brightness=brightness))


def move_objects(world: World, fraction: float, rng: np.random.Generator,
                 keep_clear_xy: npt.NDArray[np.float64]
                 ) -> tuple[World, tuple[int, ...], tuple[int, ...]]:
    """Move ``round(fraction * count)`` of the movable objects, chosen at random.

    Args:
        world: the world.
        fraction: share moved, in [0, 1].
        rng: picks the objects and their new places.
        keep_clear_xy: (K, 2) points kept :data:`KEEP_CLEAR_M` clear, m.

    Returns:
        The world with the objects moved, the indices of those moved and of those
        that found no place (see :class:`ChangedWorld`).

    Raises:
        ValueError: ``fraction`` > 0 in a world without movable objects.
    """
    movable = movable_indices(world)
    require(fraction == 0.0 or bool(movable),
            f"world '{world.name}' has no movable objects to move")
    chosen = rng.choice(movable, size=round(fraction * len(movable)), replace=False)
    moved: list[int] = []
    stuck: list[int] = []
    for index in sorted(int(i) for i in chosen):
        placed = _placed_elsewhere(world, index, rng, keep_clear_xy)
        if placed is None:
            stuck.append(index)
        else:
            world = placed
            moved.append(index)
    return world, tuple(moved), tuple(stuck)


def movable_indices(world: World) -> tuple[int, ...]:
    """Indices of the objects of ``world.furniture`` that may move (rule 4: all of them)."""
    return tuple(range(len(world.furniture)))


def _placed_elsewhere(world: World, index: int, rng: np.random.Generator,
                      keep_clear_xy: npt.NDArray[np.float64]) -> World | None:
    """``world`` with object ``index`` at a new place that keeps rule 2, or None."""
    objects = world.furniture
    box = objects[index]
    others = objects[:index] + objects[index + 1:]
    without = replace(world, furniture=others)
    free = FreeSpaceMap.from_world(without)
    other_corners = without.furniture_corners()
    for _ in range(MOVE_TRIES):
        radius, bearing = MOVE_MAX_M * math.sqrt(rng.uniform()), rng.uniform(0, 2 * math.pi)
        candidate = replace(
            box,
            center=(box.center[0] + radius * math.cos(bearing),
                    box.center[1] + radius * math.sin(bearing)),
            yaw_deg=box.yaw_deg + rng.uniform(-TURN_MAX_DEG, TURN_MAX_DEG),
        )
        if not _fits(candidate, world, free, other_corners, keep_clear_xy):
            continue
        try:
            return replace(world, furniture=(*objects[:index], candidate, *objects[index + 1:]))
        except ValueError:  # too near a route or the start, or cuts a route off (rule 1)
            continue
    return None


def _fits(box: Box, world: World, free: FreeSpaceMap, other_corners: npt.NDArray[np.float64],
          keep_clear_xy: npt.NDArray[np.float64]) -> bool:
    """Whether ``box`` stands in reachable free space, clear of walls, the other objects
    (corners (F, 4, 2)) and the kept-clear points."""
    corners = box_corners(box.center, box.size, box.yaw_deg)
    edge_a, edge_b = polygon_edges(corners[None])
    # The footprint's edges sampled every 5 cm, and its centre, lie in reachable cells.
    steps = np.linspace(0.0, 1.0, max(2, math.ceil(max(box.size) / 0.05)))[:, None, None]
    outline = (edge_a[None] + steps * (edge_b - edge_a)[None]).reshape(-1, 2)
    if not free.is_reachable(np.vstack([outline, [box.center]])).all():
        return False
    walls_a = np.array([w.start for w in world.walls], dtype=float)
    walls_b = np.array([w.end for w in world.walls], dtype=float)
    wall_gap = point_segment_distances(outline, walls_a, walls_b).min() - WALL_HALF_THICKNESS_M
    if wall_gap < MOVE_GAP_M:
        return False
    if len(other_corners):
        other_a, other_b = polygon_edges(other_corners)
        if point_segment_distances(outline, other_a, other_b).min() < MOVE_GAP_M:
            return False
        if points_in_polygons(outline, other_corners).any():
            return False
        if points_in_polygons(other_corners.reshape(-1, 2), corners[None]).any():
            return False
    if len(keep_clear_xy):
        near = point_segment_distances(keep_clear_xy, edge_a, edge_b).min()
        if near < KEEP_CLEAR_M or points_in_polygons(keep_clear_xy, corners[None]).any():
            return False
    return True
