"""The P3-AT's two sonar arrays: a firing schedule and one pymunk ray per ping.

Rules:

1. Both arrays (front 0-7, rear 8-15) fire together, one transducer each every
   ``sonar_cycle_ns`` (40 ms: a whole ring in 320 ms), in index order, as the
   firmware's default polling sequence; so a 100 ms SIP carries four to six new
   readings, not all sixteen.
2. A ping is one ray from the transducer (``p3at.SONAR_POSES``, on the true pose)
   along its axis, against walls, furniture and people
   (:data:`~sim.simulation.OCCLUDER_FILTER`); the range is to the first surface,
   plus Gaussian noise, or ``sonar_max_range_m`` when nothing is that close. A real
   sonar's 30 degree cone is not modelled: an obstacle off the axis is not seen.
3. New readings wait for the next SIP; a transducer that fires again first
   replaces its reading. Turning the sonar off drops them.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from shared.aria.p3at import SONAR_POSES, SONARS_PER_ARRAY
from shared.pose import Pose2
from sim.config import EmulatorConfig
from sim.simulation import OCCLUDER_FILTER


class SonarRing:
    """The 16 sonars of one robot.

    Args:
        space: the simulation's pymunk space.
        config: range, noise and firing cycle.
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

    @property
    def enabled(self) -> bool:
        """Whether the arrays fire (the SONAR command; on at power-up)."""
        return self._enabled

    def enable(self, on: bool) -> None:
        """Start or stop firing; stopping drops the readings not yet sent (rule 3)."""
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
        """One ping of sonar ``number`` from the true pose, world frame: range, m (rule 2)."""
        x, y, yaw = pose_w
        sx, sy, heading = SONAR_POSES[number]
        c, s = math.cos(yaw), math.sin(yaw)
        start = (x + c * sx - s * sy, y + s * sx + c * sy)
        max_range = self._config.sonar_max_range_m
        axis = yaw + heading
        end = (start[0] + max_range * math.cos(axis), start[1] + max_range * math.sin(axis))
        hit = self._space.segment_query_first(start, end, 0.0, OCCLUDER_FILTER)
        if hit is None:
            return max_range
        noisy = hit.alpha * max_range + self._config.sonar_noise_m * float(self._rng.normal())
        return min(max_range, max(0.0, noisy))
