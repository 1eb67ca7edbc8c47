"""People walking about: kinematic pymunk circles that occlude landmarks and can bump the robot.

Rules:

1. A person walks in a straight line at ``speed_m_s`` to a goal, then picks the
   next one; on arrival it sometimes pauses (probability :data:`PAUSE_PROBABILITY`,
   for :data:`PAUSE_S` seconds, uniform).
2. Goals are drawn uniformly over the free space reachable from the robot's
   start (:class:`~sim.free_space.FreeSpaceMap`) with room for the person's body,
   and accepted only when the straight walk there keeps the person's body clear
   of walls and furniture (checked on the map's clearance raster). So people
   never walk through walls or furniture. A goal whose path passes the robot's
   current position closely is refused too, unless it leads away from the robot.
   With no acceptable goal among :data:`GOAL_TRIES` draws the person waits
   half a second and tries again.
3. People yield to the robot (``config.avoid_robot``). Each step a person looks
   along their motion relative to the robot (their walk minus the robot's
   velocity): if their body, swept ``config.clearance_m`` that way, would touch
   the robot's box while closing in, they

   - stop and wait, when standing still is safe (the robot is not coming at
     them); after ``config.yield_patience_s`` of waiting they walk off to
     another goal (rule 2 refuses goals towards the robot);
   - otherwise step aside: walk square to the robot's motion, away from its
     line (the other side if that way is not clear), until their body is
     :data:`SIDESTEP_MARGIN_M` beyond the robot's half-diagonal from that line,
     or, where walls leave less room, as far as they fit clear of the robot's
     width; then pick a new goal. With nowhere clear to go they stand still.
4. People are kinematic: nothing stops them, and a person who walks into the
   robot pushes it (that is how people bump the robot; with ``avoid_robot``
   False, or a robot turning into them). On that contact the person stops,
   waits :data:`BUMP_PAUSE_S` and walks off elsewhere.
5. People pass through each other (kinematic bodies do not collide).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pymunk

from shared.errors import ConfigError
from sim._geometry import point_segment_distances
from sim._shapes import Category, tag
from sim.config import PeopleConfig
from sim.free_space import FreeSpaceMap

PAUSE_PROBABILITY = 0.3
"""Chance of pausing on reaching a goal."""
PAUSE_S = (1.0, 4.0)
"""Range of a pause, s."""
BUMP_PAUSE_S = 1.0
"""Stop after walking into the robot, s."""
GOAL_TRIES = 8
"""Goals drawn per attempt."""
RETRY_S = 0.5
"""Wait before trying again when no goal was acceptable, s."""
SIDESTEP_MARGIN_M = 0.3
"""Room a sidestepping person leaves between their body and the robot's half-diagonal, m."""

_BODY_CLEARANCE_M = 0.1  # room left between a person and walls or furniture
_SIDESTEP_TRIES = 4  # sidestep lengths tried, from the full one down to just clear
_START_CLEARANCE_M = 1.5  # people start at least this far from the robot
_ROBOT_PASS_M = 0.5  # a goal path passes the robot's centre no closer than radius + this
_MIN_WALK_M = 1.0  # goals nearer than this are not worth walking to
_STILL_M_S = 1e-3  # relative speeds below this are standing still


class People:
    """The people of a simulation; see the module docstring for their rules.

    Args:
        space: the simulation's space (one kinematic body and circle per person).
        free_space: where people may go.
        config: count, speed, radius and height.
        rng: source of start places, goals and pauses.
        robot: the robot's shape in ``space`` (its body gives position and velocity).
    """

    def __init__(
        self,
        space: pymunk.Space,
        free_space: FreeSpaceMap,
        config: PeopleConfig,
        rng: np.random.Generator,
        robot: pymunk.Poly,
    ) -> None:
        self.config = config
        self._space = space
        self._free_space = free_space
        self._rng = rng
        self._robot = robot
        self._robot_half_diagonal_m = max(v.length for v in robot.get_vertices())
        self._robot_width_m = 2 * max(abs(v.y) for v in robot.get_vertices())
        self._bodies: list[pymunk.Body] = []
        self._index: dict[pymunk.Shape, int] = {}
        self._goals: list[tuple[float, float] | None] = [None] * config.count
        self._wait_s = [0.0] * config.count
        self._blocked_s = [0.0] * config.count
        self._sidestepping = [False] * config.count
        self._headings = np.zeros(config.count)  # facing +x until they walk
        self._walked_m = np.zeros(config.count)
        for i, (x, y) in enumerate(self._start_places()):
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = (float(x), float(y))
            shape = pymunk.Circle(body, config.radius_m)
            tag(shape, Category.PERSON, config.height_m)
            space.add(body, shape)
            self._bodies.append(body)
            self._index[shape] = i
        space.on_collision(int(Category.PERSON), int(Category.ROBOT), begin=self._on_bump)

    def __len__(self) -> int:
        return len(self._bodies)

    def positions(self) -> npt.NDArray[np.float64]:
        """Current positions (M, 2), world frame, m."""
        return np.array([tuple(b.position) for b in self._bodies], dtype=float).reshape(-1, 2)

    def headings(self) -> npt.NDArray[np.float64]:
        """The way each person faces (M,), world frame, rad: their walking direction, kept
        while they stand."""
        return self._headings.copy()

    def walked_m(self) -> npt.NDArray[np.float64]:
        """Distance each person has walked (M,), m (the phase of their gait)."""
        return self._walked_m.copy()

    def index_of(self, shape: pymunk.Shape) -> int | None:
        """Which person ``shape`` is, or None."""
        return self._index.get(shape)

    def place(
        self, index: int, position_xy: tuple[float, float], goal_xy: tuple[float, float]
    ) -> None:
        """Put person ``index`` at ``position_xy`` walking to ``goal_xy`` (for scenarios and tests).

        The walk is not checked against walls: the caller chooses it.
        """
        body = self._bodies[index]
        body.position = position_xy
        body.velocity = (0.0, 0.0)
        self._space.reindex_shapes_for_body(body)
        self._goals[index] = (float(goal_xy[0]), float(goal_xy[1]))
        self._wait_s[index] = 0.0
        self._blocked_s[index] = 0.0
        self._sidestepping[index] = False

    def hold(self, index: int, seconds: float) -> None:
        """Person ``index`` stands still for ``seconds``, then walks on to their goal (for
        scenarios: someone standing in a corridor)."""
        self._wait_s[index] = float(seconds)

    def clear_robot_start(self) -> None:
        """Move anyone standing within :data:`_START_CLEARANCE_M` of the robot to a new start
        place (call after the robot was placed somewhere else than where people started)."""
        robot = np.array(self._robot.body.position, dtype=float)
        for i, body in enumerate(self._bodies):
            if np.hypot(*(np.array(body.position, dtype=float) - robot)) >= _START_CLEARANCE_M:
                continue
            others = [np.array(b.position, dtype=float) for j, b in enumerate(self._bodies)
                      if j != i]
            for _ in range(100):
                p = self._sample(1)[0]
                if self._free_start(p, others):
                    self.place(i, (p[0], p[1]), (p[0], p[1]))  # arrived: picks a goal next step
                    break

    # -- the step ---------------------------------------------------------------------

    def before_step(self, dt_s: float) -> None:
        """Set each person's velocity for the coming step."""
        for i, body in enumerate(self._bodies):
            velocity = self._walk(i, body.position, dt_s)
            if self.config.avoid_robot and not self._sidestepping[i]:
                velocity = self._yield(i, body.position, velocity, dt_s)
            body.velocity = velocity
            speed = velocity.length
            if speed > _STILL_M_S:
                self._headings[i] = velocity.angle
                self._walked_m[i] += speed * dt_s

    def _walk(self, i: int, position: pymunk.Vec2d, dt_s: float) -> pymunk.Vec2d:
        """Person ``i``'s velocity by rules 1-2 (pauses, goals), world frame, m/s."""
        if self._wait_s[i] > 0:
            self._wait_s[i] -= dt_s
            return pymunk.Vec2d(0.0, 0.0)
        goal = self._goals[i]
        if goal is None:
            goal = self._goals[i] = self._pick_goal(position)
            if goal is None:
                self._wait_s[i] = RETRY_S
                return pymunk.Vec2d(0.0, 0.0)
        to_goal = pymunk.Vec2d(*goal) - position
        distance = to_goal.length
        speed = self.config.speed_m_s
        if distance <= speed * dt_s:  # arrive exactly at the end of this step
            self._goals[i] = None
            self._sidestepping[i] = False
            if self._rng.random() < PAUSE_PROBABILITY:
                self._wait_s[i] = float(self._rng.uniform(*PAUSE_S))
            return to_goal / dt_s
        return to_goal * (speed / distance)

    # -- yielding to the robot ----------------------------------------------------------

    def _yield(
        self, i: int, position: pymunk.Vec2d, velocity: pymunk.Vec2d, dt_s: float
    ) -> pymunk.Vec2d:
        """Rule 3: ``velocity`` (world frame, m/s) if it keeps clear of the robot, else a yield."""
        robot_velocity = self._robot.body.velocity
        if not self._closing_in(position, velocity - robot_velocity):
            self._blocked_s[i] = 0.0
            return velocity
        if not self._closing_in(position, -robot_velocity):  # standing still is safe
            self._blocked_s[i] += dt_s
            if self._blocked_s[i] >= self.config.yield_patience_s:
                self._goals[i] = None
                self._blocked_s[i] = 0.0
            return pymunk.Vec2d(0.0, 0.0)
        self._blocked_s[i] = 0.0
        speed = self.config.speed_m_s
        aside = self._sidestep_goal(position, robot_velocity) if speed > 0 else None
        if aside is None:
            return pymunk.Vec2d(0.0, 0.0)
        self._goals[i] = aside
        self._wait_s[i] = 0.0
        self._sidestepping[i] = True
        return (pymunk.Vec2d(*aside) - position).scale_to_length(speed)

    def _closing_in(self, position: pymunk.Vec2d, relative_velocity: pymunk.Vec2d) -> bool:
        """Whether moving at ``relative_velocity`` (person minus robot, m/s) nears the robot.

        True when the person's body, swept ``clearance_m`` along that direction,
        touches the robot's box, and the motion shortens the gap between them.
        """
        if relative_velocity.length < _STILL_M_S:
            return False
        nearest = self._robot.point_query(position)
        if relative_velocity.dot(nearest.gradient) >= 0:  # moving away from the box
            return False
        ahead = position + relative_velocity.scale_to_length(self.config.clearance_m)
        hit = self._robot.segment_query(position, ahead, self.config.radius_m)
        return hit is not None

    def _sidestep_goal(
        self, position: pymunk.Vec2d, robot_velocity: pymunk.Vec2d
    ) -> tuple[float, float] | None:
        """Where to step, square to the robot's motion and clear of its path, or None.

        The full sidestep first, either side; where walls leave less room (a 2 m
        corridor), as far as the person fits, still clear of the robot's box.
        """
        left = robot_velocity.perpendicular_normal()
        lateral = (position - self._robot.body.position).dot(left)
        half_width = 0.5 * self._robot_width_m + self.config.radius_m
        full = self._robot_half_diagonal_m + self.config.radius_m + SIDESTEP_MARGIN_M
        side = 1.0 if lateral >= 0 else -1.0
        for reach in np.linspace(full, half_width + _BODY_CLEARANCE_M, _SIDESTEP_TRIES):
            for sign in (side, -side):
                goal = position + left * (sign * reach - lateral)
                start, end = (position.x, position.y), (goal.x, goal.y)
                if self._free_space.path_is_clear(
                    start, end, self.config.radius_m + 0.5 * _BODY_CLEARANCE_M
                ):
                    return end
        return None

    def _on_bump(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        i = self._index.get(arbiter.shapes[0])
        if i is not None:
            self._goals[i] = None
            self._sidestepping[i] = False
            self._wait_s[i] = BUMP_PAUSE_S
            self._bodies[i].velocity = (0.0, 0.0)

    # -- choosing where to go -----------------------------------------------------------

    def _start_places(self) -> npt.NDArray[np.float64]:
        """Start positions: clear of walls, furniture, the robot and each other."""
        r = self.config.radius_m
        places: list[npt.NDArray[np.float64]] = []
        for _ in range(100 * self.config.count):
            p = self._sample(1)[0]
            if self._free_start(p, places):
                places.append(p)
                if len(places) == self.config.count:
                    break
        if len(places) < self.config.count:
            raise ConfigError(
                "people", f"cannot place {self.config.count} people of radius {r} m in this world"
            )
        return np.array(places, dtype=float).reshape(-1, 2)

    def _free_start(self, p: npt.NDArray[np.float64],
                    others: list[npt.NDArray[np.float64]]) -> bool:
        """``p`` (x_m, y_m) is at least :data:`_START_CLEARANCE_M` from the robot and a body
        width from every one of ``others``."""
        robot = np.array(self._robot.body.position, dtype=float)
        return bool(np.hypot(*(p - robot)) >= _START_CLEARANCE_M) and all(
            np.hypot(*(p - q)) >= 2 * self.config.radius_m for q in others)

    def _sample(self, count: int) -> npt.NDArray[np.float64]:
        try:
            return self._free_space.sample_points(
                self._rng, count, self.config.radius_m + _BODY_CLEARANCE_M
            )
        except ValueError as e:
            raise ConfigError("people", str(e)) from None

    def _pick_goal(self, position: pymunk.Vec2d) -> tuple[float, float] | None:
        here = np.array([position.x, position.y])
        robot = np.array(self._robot.body.position, dtype=float)
        keep_off = self.config.radius_m + _ROBOT_PASS_M
        for goal in self._sample(GOAL_TRIES):
            if np.hypot(*(goal - here)) < _MIN_WALK_M:
                continue
            passes = point_segment_distances(robot[None, :], here[None, :], goal[None, :])[0, 0]
            if passes < keep_off and np.dot(goal - here, robot - here) > 0:
                continue
            path = (float(here[0]), float(here[1])), (float(goal[0]), float(goal[1]))
            if self._free_space.path_is_clear(
                *path, self.config.radius_m + 0.5 * _BODY_CLEARANCE_M
            ):
                return path[1]
        return None
