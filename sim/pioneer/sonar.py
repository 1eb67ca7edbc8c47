"""The P3-AT's two sonar arrays: a firing schedule and a cone of pymunk rays per ping.

Rules:

1. Both arrays (front 0-7, rear 8-15) fire together, one transducer each every
   ``sonar_cycle_ns`` (40 ms: a whole ring in 320 ms), in index order, as the
   firmware's default polling sequence; so a 100 ms SIP carries four to six new
   readings, not all sixteen.
2. **The cone.** A ping is ``sonar_rays`` rays from the transducer
   (``p3at.SONAR_POSES``, on the true pose), spread evenly across a cone
   ``sonar_beam_width_deg`` wide about its axis, each stopped by the first wall,
   piece of furniture, object or person it meets (:data:`SONAR_FILTER`). The
   reading is the nearest echo among the rays, plus Gaussian noise
   (``sonar_noise_m``), within [0, ``sonar_max_range_m``]; with no echo it is
   ``sonar_max_range_m``. An obstacle off the axis but inside the cone is seen, at
   its own range (a real sonar cannot tell the bearing within its cone either).
3. **Specular misses.** A ray meeting a flat surface (a wall segment, a furniture or
   object polygon) further than ``sonar_critical_angle_deg`` from the surface's
   normal (pymunk's hit normal) gives no echo: the sound glances away, and its
   further path (multipath) is not followed. So a wall met at grazing incidence
   can vanish from a side sonar, as on a real robot. Round shapes (people, tree
   trunks) send some sound back whatever the angle: they always echo.
4. **Minimum range.** A ray whose surface is nearer than ``sonar_min_range_m``
   gives no echo: it returns while the transducer still rings and the receiver is
   blanked. A transducer pressed against an obstacle therefore reads the nearest
   farther echo in its cone, or ``sonar_max_range_m``: the ring is blind up close,
   and the bumpers are what catch it there.
5. **Silent obstacles.** A placed object whose ``sonar`` is false is not met by the
   rays at all (:mod:`sim._shapes`): they pass through it to what lies behind.
6. New readings wait for the next SIP; a transducer that fires again first
   replaces its reading. Turning the sonar off drops them.

Cost: a ping of 7 rays takes about 27 us in the lab and in the campus (one
``segment_query_first`` per ray, 5 us each; measured on a shared 2-core machine), so
the ring's 50 pings a second cost about 1.4 ms of CPU per second.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from shared.aria.p3at import SONAR_POSES, SONARS_PER_ARRAY
from shared.pose import Pose2
from sim._shapes import Category
from sim.config import EmulatorConfig

SONAR_FILTER = pymunk.ShapeFilter(
    categories=int(Category.SONAR),
    mask=int(Category.WALL | Category.FURNITURE | Category.PERSON),
)
"""Ray-query filter of a ping: walls, furniture, objects and people that echo (rule 5)."""


class SonarRing:
    """The 16 sonars of one robot.

    Args:
        space: the simulation's pymunk space.
        config: range, cone, noise and firing cycle.
        rng: source of the range noise.
    """

    def __init__(self, space: pymunk.Space, config: EmulatorConfig, rng: np.random.Generator):
        self._space = space
        self._config = config
        self._rng = rng
        self._enabled = True
        self._next_fire_ns: int | None = None
        self._next_index = 0
        self._pending: dict[int, float] = {}
        half = math.radians(config.sonar_beam_width_deg) / 2
        rays = config.sonar_rays
        self._ray_offsets_rad = (  # off the axis, rad: the cone's edges included
            tuple(-half + 2 * half * k / (rays - 1) for k in range(rays)) if rays > 1 else (0.0,))
        self._cos_critical = math.cos(math.radians(config.sonar_critical_angle_deg))

    @property
    def enabled(self) -> bool:
        """Whether the arrays fire (the SONAR command; on at power-up)."""
        return self._enabled

    def enable(self, on: bool) -> None:
        """Start or stop firing; stopping drops the readings not yet sent (rule 6)."""
        self._enabled = on
        if not on:
            self._pending.clear()
            self._next_fire_ns = None

    def fire_due(self, now_ns: int, pose_w: Pose2) -> None:
        """Fire the pings due by ``now_ns`` (ns) from the robot's true pose, world frame."""
        if not self._enabled:
            return
        if self._next_fire_ns is None:
            self._next_fire_ns = now_ns
        while self._next_fire_ns <= now_ns:
            front = self._next_index
            for number in (front, front + SONARS_PER_ARRAY):
                self._pending.pop(number, None)  # re-insert: readings stay in firing order
                self._pending[number] = self.range_m(number, pose_w)
            self._next_index = (front + 1) % SONARS_PER_ARRAY
            self._next_fire_ns += self._config.sonar_cycle_ns

    def take_readings(self) -> list[tuple[int, float]]:
        """The new readings since the last call, as (sonar number, range_m), oldest first."""
        readings = list(self._pending.items())
        self._pending.clear()
        return readings

    def range_m(self, number: int, pose_w: Pose2) -> float:
        """One ping of sonar ``number`` from the true pose, world frame: range, m (rules 2-5)."""
        max_range = self._config.sonar_max_range_m
        echo = self.echo_m(number, pose_w)
        if echo is None:
            return max_range
        noisy = echo + self._config.sonar_noise_m * float(self._rng.normal())
        return min(max_range, max(0.0, noisy))

    def echo_m(self, number: int, pose_w: Pose2) -> float | None:
        """The nearest echo in sonar ``number``'s cone from the true pose, world frame, m,
        noise-free; None when no ray echoes (rules 2-5)."""
        x, y, yaw = pose_w
        sx, sy, heading = SONAR_POSES[number]
        c, s = math.cos(yaw), math.sin(yaw)
        start = (x + c * sx - s * sy, y + s * sx + c * sy)
        config = self._config
        max_range, min_range = config.sonar_max_range_m, config.sonar_min_range_m
        nearest: float | None = None
        for offset in self._ray_offsets_rad:
            dx, dy = math.cos(yaw + heading + offset), math.sin(yaw + heading + offset)
            end = (start[0] + max_range * dx, start[1] + max_range * dy)
            hit = self._space.segment_query_first(start, end, 0.0, SONAR_FILTER)
            if hit is None:
                continue
            distance = hit.alpha * max_range
            if distance < min_range or (nearest is not None and distance >= nearest):
                continue
            # Incidence: the angle between the ray and the surface normal (cos = -d . n).
            facing = -(dx * hit.normal.x + dy * hit.normal.y)
            if facing < self._cos_critical and not isinstance(hit.shape, pymunk.Circle):
                continue
            nearest = distance
        return nearest
