"""The simulation: one pymunk space with the world, the robot and the people, at a fixed step.

Rules:

1. **Seeding.** ``np.random.default_rng(config.seed)`` spawns independent child
   generators, in this order, for the landmark field, the odometry errors and
   the people. Each part draws only from its own, so changing the number of
   people changes neither the landmarks nor the odometry noise.
2. **Time** is an integer count of nanoseconds since the start, advanced only
   by :meth:`Simulation.step`. :meth:`Simulation.step_until` takes fixed steps of
   ``config.physics_dt_ns`` until the deadline is reached or passed (time stays
   on the step grid; no float accumulation).
3. **A step**: the step hooks run (:meth:`Simulation.add_step_hook`: a controller
   such as the emulated Pioneer's firmware commands the body here), the body ramps
   its set-points and sets its velocity, the people set theirs, pymunk integrates,
   then the body reads its actual motion (truth, bumpers, stall, odometry).
4. **Shapes.** Walls are static segments (radius
   :data:`~sim.free_space.WALL_HALF_THICKNESS_M`), furniture static boxes, people
   kinematic circles, the robot a dynamic box. Each carries its height
   (:meth:`Simulation.occluder_height`); :data:`OCCLUDER_FILTER` makes ray queries see
   walls, furniture and people but not the robot. A placed object whose ``sonar`` is
   false is silent to the sonar's queries (:mod:`sim._shapes`), solid to the rest.
5. **Objects placed while it runs** (:meth:`Simulation.add_object`, such as a box put
   on a route after it was taught) are static boxes like the world's objects, with an
   id; :meth:`Simulation.remove_object` takes one away. Each change bumps
   :attr:`Simulation.objects_revision`, so a renderer knows to redraw its scene. The
   people do not know of them (their free-space map is the world's): they walk
   through them, as they walk through nothing else.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np
import numpy.typing as npt
import pymunk

from shared.errors import ConfigError
from shared.pose import Pose2
from sim._geometry import box_corners
from sim._shapes import Category, category_of, height_of, tag
from sim.body import PioneerBody
from sim.config import SimConfig
from sim.decor import PlacedObject
from sim.free_space import WALL_HALF_THICKNESS_M, FreeSpaceMap
from sim.landmarks import LandmarkField, generate_landmarks
from sim.people import People
from sim.world import World

OCCLUDER_FILTER = pymunk.ShapeFilter(mask=int(Category.WALL | Category.FURNITURE | Category.PERSON))
"""Ray-query filter that hits walls, furniture and people, never the robot."""

_STATIC_FILTER = pymunk.ShapeFilter(mask=int(Category.WALL | Category.FURNITURE))
_COLLISION_SLOP_M = 0.002  # pymunk's allowed overlap (its default, 0.1, assumes pixels)
_WALL_FRICTION = 0.5


class Simulation:
    """A world, the robot's body, the people and the landmark field, in lock-step.

    Args:
        world: the place.
        config: seed, physics step, body, odometry, people and landmark settings.
        landmark_world: the world the landmark patches are placed in; None: ``world``.
            A repeat after a scene change (:mod:`sim.scene_change`) passes the taught
            world, so that the patches stay where they were taught (moving an object
            would otherwise redraw the whole field).

    Attributes:
        world: the world.
        config: the configuration.
        space: the pymunk space.
        free_space: the reachable free space of the world.
        landmarks: the landmark field.
        body: the robot's body.
        people: the people.
        light_gain_at: the scene's light at a simulation time (ns), relative to the
            world's lighting: 1 unless a scenario changes the light during the run
            (:meth:`sim.scene_change.LightingChange.gain_at`); the renderer applies it.
    """

    def __init__(self, world: World, config: SimConfig,
                 landmark_world: World | None = None) -> None:
        self.world = world
        self.config = config
        landmark_rng, odometry_rng, people_rng = np.random.default_rng(config.seed).spawn(3)
        self.space = pymunk.Space()
        self.space.collision_slop = _COLLISION_SLOP_M
        self._add_walls_and_furniture()
        self.free_space = FreeSpaceMap.from_world(world)
        self.landmarks: LandmarkField = generate_landmarks(
            world if landmark_world is None else landmark_world,
            landmark_rng,
            config.landmark_density_scale,
            self.free_space if landmark_world is None else None,
        )
        self.body = PioneerBody(self.space, config.body, config.odometry, world.start, odometry_rng)
        self.people = People(
            self.space, self.free_space, config.people, people_rng, self.body.shape
        )
        self._now_ns = 0
        self._dt_s = config.physics_dt_ns / 1e9
        self._step_hooks: list[Callable[[int, int], None]] = []
        self.light_gain_at: Callable[[int], float] = _steady_light
        self._added: dict[int, tuple[PlacedObject, pymunk.Shape]] = {}
        self._next_object_id = 1
        self._objects_revision = 0

    def _add_walls_and_furniture(self) -> None:
        static = self.space.static_body
        for wall in self.world.walls:
            segment = pymunk.Segment(static, wall.start, wall.end, WALL_HALF_THICKNESS_M)
            segment.friction = _WALL_FRICTION
            tag(segment, Category.WALL, wall.height_m)
            self.space.add(segment)
        for box, corners in zip(self.world.furniture, self.world.furniture_corners(), strict=True):
            poly = pymunk.Poly(static, [tuple(c) for c in corners])
            poly.friction = _WALL_FRICTION
            tag(poly, Category.FURNITURE, box.height_m)
            self.space.add(poly)
        for obj, corners in zip(self.world.objects, self.world.object_corners(), strict=True):
            self.space.add(self._object_shape(obj, corners))
        for tree in self.world.trees:
            trunk = pymunk.Circle(static, tree.trunk_radius_m, tree.at)
            trunk.friction = _WALL_FRICTION
            tag(trunk, Category.FURNITURE, tree.trunk_height_m + tree.crown_radius_m)
            self.space.add(trunk)

    def _object_shape(self, obj: PlacedObject, corners: npt.NDArray[np.float64]) -> pymunk.Poly:
        """The static polygon of a placed object with footprint ``corners`` (4, 2), m."""
        poly = pymunk.Poly(self.space.static_body, [tuple(c) for c in corners])
        poly.friction = _WALL_FRICTION
        tag(poly, Category.FURNITURE, obj.elevation_m + obj.height_m, sonar_echo=obj.sonar)
        return poly

    # -- objects placed while running (rule 5) -----------------------------------------

    @property
    def added_objects(self) -> Mapping[int, PlacedObject]:
        """The objects placed while running, by id, oldest first (read-only)."""
        return MappingProxyType({i: obj for i, (obj, _) in self._added.items()})

    @property
    def objects_revision(self) -> int:
        """A count of the objects placed and removed while running (rule 5)."""
        return self._objects_revision

    def add_object(self, obj: PlacedObject) -> int:
        """Put ``obj`` in the world now (solid, heard by the sonar unless ``obj.sonar`` is
        false, drawn by a renderer from its next frame); returns its id (1, 2, ...).

        Raises:
            ConfigError: its footprint overlaps the robot.
        """
        poly = self._object_shape(obj, box_corners(*obj.footprint()))
        hits = self.space.shape_query(poly)
        if any(h.shape is self.body.shape for h in hits):
            (x, y), (length, width), _ = obj.footprint()
            raise ConfigError("object", f"a {length:g} x {width:g} m {obj.kind} at "
                                        f"({x:g}, {y:g}) overlaps the robot")
        self.space.add(poly)
        object_id = self._next_object_id
        self._next_object_id += 1
        self._added[object_id] = (obj, poly)
        self._objects_revision += 1
        return object_id

    def remove_object(self, object_id: int) -> PlacedObject:
        """Take away the object placed with id ``object_id``; returns it.

        Raises:
            ConfigError: no object placed while running has that id.
        """
        if object_id not in self._added:
            placed = ", ".join(map(str, self._added)) or "none"
            raise ConfigError(f"object {object_id}",
                              f"no object placed while running has this id (placed: {placed})")
        obj, poly = self._added.pop(object_id)
        self.space.remove(poly)
        self._objects_revision += 1
        return obj

    # -- time -------------------------------------------------------------------------

    @property
    def now_ns(self) -> int:
        """Simulation time since the start, ns."""
        return self._now_ns

    def step(self, dt_ns: int | None = None) -> None:
        """Advance by one physics step of ``dt_ns`` (default ``config.physics_dt_ns``).

        Raises:
            ValueError: ``dt_ns`` is not a positive integer.
        """
        if dt_ns is None:
            dt_ns, dt_s = self.config.physics_dt_ns, self._dt_s
        else:
            if isinstance(dt_ns, bool) or not isinstance(dt_ns, int | np.integer) or dt_ns <= 0:
                raise ValueError(f"dt_ns must be a positive integer, got {dt_ns!r}")
            dt_ns, dt_s = int(dt_ns), dt_ns / 1e9
        for hook in self._step_hooks:
            hook(self._now_ns, dt_ns)
        self.body.before_step(dt_s)
        self.people.before_step(dt_s)
        self.space.step(dt_s)
        self.body.after_step(dt_s)
        self._now_ns += dt_ns

    def add_step_hook(self, hook: Callable[[int, int], None]) -> None:
        """Call ``hook(now_ns, dt_ns)`` at the start of every physics step (rule 3).

        Hooks run in the order they were added, with the time the step starts from
        and its length, ns; they may command the body.
        """
        self._step_hooks.append(hook)

    def step_until(self, deadline_ns: int) -> int:
        """Take fixed steps until ``now_ns >= deadline_ns``; returns the number of steps."""
        steps = 0
        while self._now_ns < deadline_ns:
            self.step()
            steps += 1
        return steps

    # -- queries for the renderer and scenarios ---------------------------------------

    @staticmethod
    def occluder_height(shape: pymunk.Shape) -> float:
        """Height of a wall, piece of furniture or person hit by a query, m.

        Raises:
            ValueError: ``shape`` does not belong to a simulation.
        """
        return height_of(shape)

    def is_person(self, shape: pymunk.Shape) -> bool:
        """Whether ``shape`` is one of the people."""
        return category_of(shape) == Category.PERSON

    def people_state(self) -> tuple[npt.NDArray[np.float64], float, float]:
        """People's positions (M, 2) (world frame, m), their radius (m) and height (m)."""
        return self.people.positions(), self.config.people.radius_m, self.config.people.height_m

    def place_robot(self, pose: Pose2) -> None:
        """Put the robot at rest at ``pose``; odometry restarts there (see :mod:`sim.body`).
        People standing too close to it start elsewhere.

        Raises:
            ConfigError: ``pose`` is outside the world's extent or not finite, or the robot
                would overlap a wall or furniture.
        """
        (x0, y0), (x1, y1) = self.world.extent()
        if not (x0 <= pose.x_m <= x1 and y0 <= pose.y_m <= y1 and math.isfinite(pose.yaw_rad)):
            raise ConfigError(
                "robot pose",
                f"({pose.x_m}, {pose.y_m}, {math.degrees(pose.yaw_rad)} deg) is outside world "
                f"'{self.world.name}' (x {x0:g} to {x1:g} m, y {y0:g} to {y1:g} m)",
            )
        probe_body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        probe_body.position = (pose.x_m, pose.y_m)
        probe_body.angle = pose.yaw_rad
        probe = pymunk.Poly.create_box(
            probe_body, (self.config.body.length_m, self.config.body.width_m)
        )
        probe.filter = _STATIC_FILTER
        hits = self.space.shape_query(probe)
        if hits and hits[0].shape is not None:
            kind = Category(category_of(hits[0].shape)).name.lower()
            raise ConfigError(
                "robot pose",
                f"({pose.x_m}, {pose.y_m}, {math.degrees(pose.yaw_rad)} deg) overlaps a {kind}",
            )
        self.body.place(pose)
        self.people.clear_robot_start()


def _steady_light(t_ns: int) -> float:
    """The world's light, unchanged at every time."""
    return 1.0
