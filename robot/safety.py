"""The safety layer's core: how fast the robot may go, given its sonars and bumpers (pure).

Theory of operation
-------------------

Every velocity command of the robot, a mission's or the operator's stick, passes
:meth:`SafetyGovernor.assess` before it reaches the base (``robot.safe_base``). The
governor keeps no map: it sees the latest echo of each sonar, where the robot stood
when it came, and what the robot is asked to do, and it only ever lowers the speed.
This is the reactive layer of ARIA's ``ArActionAvoidFront`` / ``ArActionLimiterForwards``
with an explicit swept corridor, a stop line and hysteresis, as in the stop-and-wait
behaviour of VT&R systems (Furgale & Barfoot 2010 waited for people in the path).

Rules (``SafetyConfig`` holds every distance and time):

1. Echoes. A sonar's echo comes from somewhere on the arc of its cone at its range
   (``beam_width_rad``). It is placed on the arc's point nearest the sensor's axis
   (ARIA's ``ArSensorReading`` convention, when nothing says otherwise) that no reading
   since the echo appeared has seen free: a reading sees nothing nearer than its range in
   the middle of its cone (``clear_width_rad``), so the readings of the neighbouring
   sonars, and of every sonar from where the robot stood a moment ago, rule out parts of
   the arc (the robot's motion is the baseline that tells where on the arc a still
   object lies: Moravec & Elfes's free-space evidence, without a map). The readings kept
   for it are those taken within ``carve_distance_m`` of where the robot stands (and in
   the last ``carve_window_ns``) since the sensor first returned about this range (a new
   echo is not placed by what the sonars saw before it came); when they rule out the
   whole arc the axis stands. The echo is fixed in the odometry frame where the robot
   stood when it arrived and seen from where the robot stands now, so a 300 ms old echo
   does not move with the robot. An echo whose axis point moved towards the robot over
   the same sonar's last two intervals between readings (each time at least
   ``approach_min_m_s``, and each step shorter than ``approach_gate_m``: a longer one, or
   a single step, is the beam finding another surface) is something walking at it: it
   counts where it will be ``approach_horizon_ns`` after now at the slower of the two
   speeds, so the robot stops before a person who walks at it instead of meeting them at
   its stop line (a sonar sees a person walking at 1 m/s up to 0.4 m late: its ring takes
   320 ms).
2. The swept corridor. Driving forward at (v, omega) the robot's centre follows the
   arc of curvature omega / v; its body sweeps the band of half-width ``half_width_m``
   + ``side_margin_m`` around that arc. An echo in the band at arc length s lies
   ``d = s - front_m`` ahead of the front. Reversing is the mirror image (rear sensors,
   ``rear_m``). Standing still, the corridor is the straight one ahead.
3. The bound. The nearest echo ahead at d: inside ``slow_distance_m`` the speed falls
   linearly with d, never below ``min_speed_ratio`` of the command, and the turn rate
   with it (the arc stays the one checked); beyond it the command passes. Forward motion
   stops at or inside ``stop_distance_m`` for an echo in the corridor's inner band,
   within ``side_stop_margin_m`` of the swept body (3 cm by default); one
   farther out, in the margin, lets the robot creep past at the slowest ratio (a safety
   laser scanner's speed-dependent fields: a bin beside the way, that the sonar cannot
   place on its cone, need not hold the robot for good), but only when it cannot lie
   within the inner band: rule 1's readings saw every point of its arc there free, and
   it is not coming towards the robot. Reversing stops for the whole corridor.
4. Hysteresis. Once stopped, forward motion stays stopped until the nearest echo
   ahead has stayed beyond ``stop_distance_m`` + ``clear_margin_m`` for
   ``clear_dwell_ns``: a noisy echo near the line does not make the robot jerk.
5. Silence is not clear. Forward motion needs a reading younger than
   ``sonar_stale_ns`` from every sensor whose axis points forward of abeam (reverse:
   aft of abeam); a base with no range sensor cannot drive forward at all.
6. Turning in place is refused (omega = 0) while an echo lies within the circle the
   robot's corners sweep, plus ``turn_margin_m``; otherwise it stays allowed, so a
   stopped robot can still face its route.
7. Bumper and emergency stop hold: a bumper pressed (its rising edge) while the robot
   moves it into the world, or did so in the last :data:`MOVING_GRACE_NS` (it hit
   something), or :meth:`SafetyGovernor.emergency_stop`, stops everything until
   :meth:`SafetyGovernor.release` (the operator re-arms or changes mode). The rear
   bumper alone (``BaseState.bumped_rear_only``) is the robot's hit only when a point of
   it moved outwards faster than :data:`BUMPER_FACE_M_S`: reversing, or the rear corners
   swinging in a turn (``rear_m`` and ``half_width_m``); driving forward on a gentle arc it
   moves away from whatever touched it. A bumper pressed while the robot stood still, or
   the rear one while it drove away, is someone walking into it ("pushed"): nothing
   moves while it stays pressed, then the way must clear as after an obstacle (rule 4),
   and a mission waits instead of ending.

:class:`~shared.interfaces.Blocked` reports the hold that stops forward motion (rules
3-5, 7), for the mission (wait, resume, give up) and telemetry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import chain
from typing import NamedTuple

import numpy as np

from robot.config import SafetyConfig
from shared.interfaces import BaseState, Blocked, RangeReading

#: A bumper pressed this soon after the robot was last allowed to move is its own hit (it
#: may still be braking: 0.33 s from 0.2 m/s on a P3-AT), ns.
MOVING_GRACE_NS = 500_000_000
#: The rear bumper moves into the world when a point of it moves outwards faster than
#: this (rule 7), m/s: a robot following its route forward turns its rear corners
#: sideways by a few mm/s.
BUMPER_FACE_M_S = 0.02
#: A reading taken within this distance and heading of the same sensor's last kept one,
#: with about its range, replaces it (rule 1: the readings of a robot standing still do
#: not pile up), m and rad.
SAME_PLACE_M = 0.02
SAME_HEADING_RAD = math.radians(2.0)
#: Where on its arc an echo is tried (rule 1), from the axis outwards: fractions of half
#: the beam's width (every 3.75 degrees of a 30-degree beam).
ARC_STEPS = np.array([0.0] + [sign * k / 4 for k in range(1, 5) for sign in (1, -1)])


@dataclass(frozen=True, slots=True)
class Assessment:
    """The bounded command and why it was bounded.

    Attributes:
        v_m_s: the forward speed the base may get, m/s.
        omega_rad_s: the turn rate the base may get, rad/s.
        blocked: the hold that stops forward motion now, or None.
        ahead_m: the nearest echo in the forward corridor's inner band (rule 3), ahead of
            the front, m (inf when none).
    """

    v_m_s: float
    omega_rad_s: float
    blocked: Blocked | None
    ahead_m: float


class SafetyGovernor:
    """Rules 1-7 for one robot; not thread-safe (``robot.safe_base`` locks it).

    Args:
        config: distances, times and the robot's footprint.
    """

    def __init__(self, config: SafetyConfig) -> None:
        self._config = config
        self._latched: Blocked | None = None  # rule 7
        self._was_bumped = False
        self._moving_until_ns: int | None = None  # rule 7: the robot may still move
        self._rear_moving_until_ns: int | None = None  # rule 7: and its rear bumper
        self._stopped_since_ns: int | None = None  # rule 4: forward motion stopped
        self._clear_since_ns: int | None = None
        self._echoes: dict[tuple[float, float, float], _Echo] = {}  # rule 1, per sensor
        # rule 1: per sensor, its readings taken near where the robot stands, (t_ns, x_m,
        # y_m, heading_rad, range_m) of the sensor in the odometry frame; how many were
        # ever kept
        self._seen: dict[tuple[float, float, float], list[_Seen]] = {}
        self._seen_count = 0
        # rule 1: the last placements, keyed by the readings they were made from
        self._placed: tuple[tuple[int, tuple[tuple[int, int], ...]],
                            list[tuple[float, float]]] | None = None

    @property
    def config(self) -> SafetyConfig:
        """The layer's settings."""
        return self._config

    @property
    def latched(self) -> Blocked | None:
        """The bumper's or emergency stop's hold in force (rule 7), or None."""
        return self._latched

    def configure(self, config: SafetyConfig) -> None:
        """New settings; the holds and the hysteresis in force stay."""
        self._config = config

    def emergency_stop(self, now_ns: int) -> None:
        """Hold everything until :meth:`release` (rule 7)."""
        if self._latched is None or self._latched.cause != "e_stop":
            self._latched = Blocked("e_stop", math.nan, now_ns)

    def release(self) -> None:
        """The operator re-armed or changed mode: the bumper's or e-stop's hold ends."""
        self._latched = None

    def assess(self, now_ns: int, state: BaseState, v_m_s: float,
               omega_rad_s: float) -> Assessment:
        """Bound the command (v_m_s, omega_rad_s) at ``now_ns`` for the base in ``state``."""
        cfg = self._config
        until_ns = self._rear_moving_until_ns if state.bumped_rear_only else self._moving_until_ns
        moving = until_ns is not None and now_ns < until_ns
        if state.bumped and not self._was_bumped and self._latched is None and moving:
            self._latched = Blocked("bumper", math.nan, now_ns)
        self._was_bumped = state.bumped
        stop_half = cfg.half_width_m + cfg.side_stop_margin_m
        half = cfg.half_width_m + cfg.side_margin_m
        points, arcs = self._echo_points(state, now_ns, reverse=v_m_s < 0)
        ahead_m = _nearest_ahead(points, v_m_s, omega_rad_s, cfg.front_m, stop_half,
                                 reverse=False)
        if stop_half < half:  # an echo in the margin stops the robot if it may lie within
            ahead_m = min(ahead_m, _nearest_doubtful(
                points, arcs, state.odom_pose, v_m_s, omega_rad_s, cfg.front_m, stop_half,
                half))
        blocked = self._forward_hold(now_ns, ahead_m, _silent(state, now_ns, cfg, reverse=False),
                                     pushed=state.bumped and self._latched is None)
        if self._latched is not None:
            return Assessment(0.0, 0.0, self._latched, ahead_m)
        if state.bumped:
            return Assessment(0.0, 0.0, blocked, ahead_m)
        v, omega = v_m_s, omega_rad_s
        if v > 0:
            # slowing down watches the whole corridor, stopping only its inner band
            slow_m = ahead_m if half == stop_half else _nearest_ahead(
                points, v_m_s, omega_rad_s, cfg.front_m, half, reverse=False)
            ratio = 0.0 if blocked is not None else _speed_ratio(slow_m, cfg)
        elif v < 0:
            behind_m = _nearest_ahead(points, v_m_s, omega_rad_s, cfg.rear_m, half,
                                      reverse=True)
            silent = _silent(state, now_ns, cfg, reverse=True)
            ratio = 0.0 if silent or behind_m <= cfg.stop_distance_m else _speed_ratio(
                behind_m, cfg)
        else:
            ratio = 1.0
        v *= ratio
        if ratio > 0.0:
            omega *= ratio  # slowing down keeps the arc the corridor was checked along
        if omega != 0.0 and _too_close_to_turn(points, cfg):
            omega = 0.0
        if v != 0.0 or omega != 0.0:
            self._moving_until_ns = now_ns + MOVING_GRACE_NS
        if max(-v + abs(omega) * cfg.half_width_m, abs(omega) * cfg.rear_m) > BUMPER_FACE_M_S:
            self._rear_moving_until_ns = now_ns + MOVING_GRACE_NS
        return Assessment(v, omega, blocked, ahead_m)

    def _forward_hold(self, now_ns: int, ahead_m: float, silent: bool,
                      pushed: bool) -> Blocked | None:
        """Rules 3-5 and 7's push: stop at the line, clear only after the margin and the
        dwell."""
        cfg = self._config
        if pushed:
            self._stopped_since_ns = self._stopped_since_ns or now_ns
            self._clear_since_ns = None
            return Blocked("pushed", math.nan, self._stopped_since_ns)
        if silent:
            self._stopped_since_ns = self._stopped_since_ns or now_ns
            self._clear_since_ns = None
            return Blocked("sonar_silent", math.nan, self._stopped_since_ns)
        if ahead_m <= cfg.stop_distance_m:
            if self._stopped_since_ns is None:
                self._stopped_since_ns = now_ns
            self._clear_since_ns = None
        elif self._stopped_since_ns is not None:
            if ahead_m <= cfg.stop_distance_m + cfg.clear_margin_m:
                self._clear_since_ns = None
            elif self._clear_since_ns is None:
                self._clear_since_ns = now_ns
            if (self._clear_since_ns is not None
                    and now_ns - self._clear_since_ns >= cfg.clear_dwell_ns):
                self._stopped_since_ns = self._clear_since_ns = None
        if self._stopped_since_ns is None:
            return None
        return Blocked("obstacle", ahead_m, self._stopped_since_ns)


    def _echo_points(self, state: BaseState, now_ns: int, reverse: bool
                     ) -> tuple[list[tuple[float, float]], list[np.ndarray | None]]:
        """Rule 1: each fresh reading's echo, (x_m, y_m) in the robot frame now, placed on
        its arc, moved ahead in time when it comes towards the robot; the robot is asked to
        reverse or not (rule 2 looks behind or ahead). With each, where on its arc it may
        lie, (K, 2) odometry frame, m: the arc's points no reading saw free (rule 3's
        creep); None where that is not known (an echo too far to place, or one coming
        towards the robot: it may be anywhere ahead)."""
        cfg = self._config
        x0, y0, yaw0 = state.odom_pose
        c0, s0 = math.cos(yaw0), math.sin(yaw0)
        fresh = [(r, self._track(r)) for r in state.ranges]
        fresh = [(r, echo) for r, echo in fresh if now_ns - r.t_ns <= cfg.sonar_stale_ns]
        self._forget(state.odom_pose, now_ns)
        placed, spans = self._placements([echo for _, echo in fresh], [
            _faces(r, reverse) for r, _ in fresh])
        points = []
        arcs: list[np.ndarray | None] = []
        for (r, echo), (wx, wy), span in zip(fresh, placed, spans, strict=True):
            to_x, to_y = x0 - wx, y0 - wy
            gap = math.hypot(to_x, to_y)
            coming = echo.approach_m_s >= cfg.approach_min_m_s
            arcs.append(None if coming else span)
            if coming and gap > 1e-9:
                # no nearer than the body's inner circle: the echo stays in front of it
                inner = min(cfg.front_m, cfg.rear_m, cfg.half_width_m)
                step = min(max(0.0, gap - inner), echo.approach_m_s * (
                    now_ns - r.t_ns + cfg.approach_horizon_ns) / 1e9)
                wx, wy = wx + to_x / gap * step, wy + to_y / gap * step
            dx, dy = wx - x0, wy - y0
            points.append((c0 * dx + s0 * dy, -s0 * dx + c0 * dy))
        return points, arcs

    def _track(self, reading: RangeReading) -> _Echo:
        """The reading's echo on its axis in the odometry frame, since when the sensor has
        seen it, and how fast it came towards where the robot stood, from the same sensor's
        previous reading (rule 1). A new reading joins the readings kept."""
        ox, oy, oyaw = reading.odom_pose
        sx, sy, sh = reading.sensor_pose
        c, s = math.cos(oyaw), math.sin(oyaw)
        at_x, at_y, heading = ox + c * sx - s * sy, oy + s * sx + c * sy, oyaw + sh
        x = at_x + reading.range_m * math.cos(heading)
        y = at_y + reading.range_m * math.sin(heading)
        before = self._echoes.get(reading.sensor_pose)
        if before is not None and (before.t_ns, before.x_m, before.y_m) == (reading.t_ns, x, y):
            return before  # the same reading as at the last command
        step = 0.0
        since_ns = reading.t_ns
        if before is not None and reading.t_ns > before.t_ns:
            moved_x, moved_y = x - before.x_m, y - before.y_m
            to_x, to_y = ox - before.x_m, oy - before.y_m
            gap = math.hypot(to_x, to_y)
            if math.hypot(moved_x, moved_y) <= self._config.approach_gate_m and gap > 1e-9:
                towards = (moved_x * to_x + moved_y * to_y) / gap
                step = max(0.0, towards * 1e9 / (reading.t_ns - before.t_ns))
            travel = math.hypot(at_x - before.at_x_m, at_y - before.at_y_m)
            turned = abs(math.remainder(heading - before.heading_rad, math.tau))
            if (abs(reading.range_m - before.range_m) <= travel + self._config.free_margin_m
                    and turned <= self._config.clear_width_rad / 2):
                since_ns = before.since_ns  # still the same thing
        approach = 0.0 if before is None else min(step, before.step_m_s)
        echo = _Echo(reading.t_ns, x, y, step, approach, at_x, at_y, heading, reading.range_m,
                     since_ns, math.hypot(sx, sy))
        self._echoes[reading.sensor_pose] = echo
        self._keep(reading.sensor_pose, _Seen(reading.t_ns, at_x, at_y, heading,
                                              reading.range_m))
        return echo

    def _keep(self, sensor: tuple[float, float, float], seen: _Seen) -> None:
        """Keep a reading for rule 1; one that says what the sensor's last kept reading
        said, from about the same place, only brings that one's time up to date."""
        kept = self._seen.setdefault(sensor, [])
        if kept:
            last = kept[-1]
            if (math.hypot(seen.x_m - last.x_m, seen.y_m - last.y_m) < SAME_PLACE_M
                    and abs(math.remainder(seen.heading_rad - last.heading_rad, math.tau))
                    < SAME_HEADING_RAD
                    and abs(seen.range_m - last.range_m) < self._config.free_margin_m / 2):
                kept[-1] = seen
                return
        kept.append(seen)
        self._seen_count += 1

    def _forget(self, odom_pose: tuple[float, float, float], now_ns: int) -> None:
        """Drop the readings rule 1 no longer uses: taken more than ``carve_distance_m``
        from where the robot stands now, or longer than ``carve_window_ns`` ago."""
        cfg = self._config
        x, y, _ = odom_pose
        for sensor, kept in self._seen.items():
            if kept and (now_ns - kept[0].t_ns > cfg.carve_window_ns or math.hypot(
                    kept[0].x_m - x, kept[0].y_m - y) > cfg.carve_distance_m):
                self._seen[sensor] = [
                    r for r in kept if now_ns - r.t_ns <= cfg.carve_window_ns
                    and math.hypot(r.x_m - x, r.y_m - y) <= cfg.carve_distance_m]

    def _placements(self, echoes: list[_Echo], ahead: list[bool]
                    ) -> tuple[list[tuple[float, float]], list[np.ndarray | None]]:
        """Rule 1: each echo's point of its arc nearest its axis that no reading kept since
        the echo appeared saw free, (x_m, y_m) in the odometry frame. The axis point when
        every point was seen free, or when the echo is too far to matter wherever it lies on
        its arc: beyond the slow-down distance from the body for a sensor facing the way
        the robot goes (``ahead``), beyond the circle rule 6 watches for the others. With
        each, the points of its arc no reading saw free ((K, 2) odometry frame, m; the axis
        point alone when every point was seen free), None for an echo too far to matter."""
        cfg = self._config
        body = max(cfg.front_m, cfg.rear_m)
        reach_ahead = body + cfg.slow_distance_m + cfg.half_width_m + cfg.side_margin_m
        reach_turning = math.hypot(body, cfg.half_width_m) + cfg.turn_margin_m
        points = [(echo.x_m, echo.y_m) for echo in echoes]
        spans: list[np.ndarray | None] = [None] * len(echoes)
        near = [i for i, echo in enumerate(echoes) if echo.range_m < echo.mount_m + (
            reach_ahead if ahead[i] else reach_turning)]
        if not near:
            return points, spans
        key = (self._seen_count, tuple((i, echoes[i].t_ns) for i in near))
        if self._placed is not None and self._placed[0] == key:
            for i, point, span in zip(near, self._placed[1], self._placed[2], strict=True):
                points[i], spans[i] = point, span
            return points, spans
        count = sum(len(kept) for kept in self._seen.values())
        seen = np.fromiter(chain.from_iterable(chain.from_iterable(self._seen.values())),
                           float, count=5 * count).reshape(count, 5)
        arcs = np.array([(echoes[i].at_x_m, echoes[i].at_y_m, echoes[i].heading_rad,
                          echoes[i].range_m, echoes[i].since_ns) for i in near])
        placed, unseen = _unseen_points(arcs, seen, cfg)
        for i, (x, y), span in zip(near, placed.tolist(), unseen, strict=True):
            if not math.isnan(x):
                points[i] = (x, y)
            free = np.isnan(span[:, 0])
            spans[i] = np.array([points[i]]) if free.all() else span[~free]
        self._placed = (key, [points[i] for i in near], [spans[i] for i in near])
        return points, spans


def _unseen_points(arcs: np.ndarray, seen: np.ndarray,
                   config: SafetyConfig) -> tuple[np.ndarray, np.ndarray]:
    """Rule 1's placement: each echo's point of its arc nearest its axis that no reading
    since the echo appeared saw free, and all those points.

    Args:
        arcs: (E, 5) the echoes: their sensor's x_m, y_m and heading_rad in the odometry
            frame, their range_m, and since when (ns) the sensor returned about that range.
        seen: (N, 5) the readings kept: t_ns, the sensor's x_m, y_m, heading_rad, range_m.
        config: the beam's and the free view's widths and the range margin.

    Returns:
        (E, 2) the points, odometry frame, m; NaN where every point was seen free.
        (E, K, 2) the arc's points (:data:`ARC_STEPS`), odometry frame, m; NaN where seen
        free.
    """
    half_clear = config.clear_width_rad / 2
    cos_h, sin_h = np.cos(seen[:, 3]), np.sin(seen[:, 3])
    # Which readings can see any of an echo's arc (E, N): the arc lies within the circle
    # around its axis point through its ends, which must reach into the reading's free
    # view (nearer than its range, and not farther from its middle than half_clear)
    mx = arcs[:, 0] + arcs[:, 3] * np.cos(arcs[:, 2])
    my = arcs[:, 1] + arcs[:, 3] * np.sin(arcs[:, 2])
    radius = (2.0 * arcs[:, 3] * math.sin(config.beam_width_rad / 4))[:, None]
    dx = mx[:, None] - seen[:, 1]
    dy = my[:, None] - seen[:, 2]
    along = dx * cos_h + dy * sin_h
    across = np.abs(dy * cos_h - dx * sin_h)
    echo, reading = np.nonzero(
        (along > -radius) & (along - radius < seen[:, 4] - config.free_margin_m)
        & (across * math.cos(half_clear) - along * math.sin(half_clear) <= radius)
        & (seen[:, 0] >= arcs[:, 4:5]))
    # The points of the arc (E, K), and which of them each of those readings saw free (P, K)
    angles = arcs[:, 2:3] + ARC_STEPS * (config.beam_width_rad / 2)
    qx = arcs[:, 0:1] + arcs[:, 3:4] * np.cos(angles)
    qy = arcs[:, 1:2] + arcs[:, 3:4] * np.sin(angles)
    seen = seen[reading]
    dx = qx[echo] - seen[:, 1:2]
    dy = qy[echo] - seen[:, 2:3]
    squared = dx * dx + dy * dy
    along = dx * cos_h[reading, None] + dy * sin_h[reading, None]  # on the reading's axis
    nearer = np.maximum(seen[:, 4:5] - config.free_margin_m, 0.0)
    free = ((squared < nearer * nearer) & (along > 0.0)
            & (along * along >= squared * math.cos(half_clear) ** 2))
    carved = np.zeros(qx.shape, bool)
    np.logical_or.at(carved, echo, free)
    first = np.argmax(~carved, axis=1)
    rows = np.arange(len(arcs))
    placed = np.stack([qx[rows, first], qy[rows, first]], axis=1)
    placed[carved[rows, first]] = np.nan
    unseen = np.stack([qx, qy], axis=2)
    unseen[carved] = np.nan
    return placed, unseen


class _Seen(NamedTuple):
    """A reading kept for rule 1: when (ns), the sensor's place and heading in the
    odometry frame (m, rad), its range (m)."""

    t_ns: int
    x_m: float
    y_m: float
    heading_rad: float
    range_m: float


@dataclass(frozen=True, slots=True)
class _Echo:
    """One sensor's latest echo: when (ns), its axis point in the odometry frame (m), how
    fast it came towards the robot since the sensor's previous echo, and the slower of that
    and the interval before (m/s, >= 0); the sensor's place and heading in the odometry
    frame (m, rad), the range (m), since when the sensor has returned about this range
    (ns), and how far the sensor sits from the robot's centre (m)."""

    t_ns: int
    x_m: float
    y_m: float
    step_m_s: float
    approach_m_s: float
    at_x_m: float
    at_y_m: float
    heading_rad: float
    range_m: float
    since_ns: int
    mount_m: float


def _faces(reading: RangeReading, reverse: bool) -> bool:
    """The sensor's axis points forward of abeam (aft of abeam when ``reverse``)."""
    ahead = math.cos(reading.sensor_pose[2])
    return ahead < 1e-6 if reverse else ahead > -1e-6


def _silent(state: BaseState, now_ns: int, config: SafetyConfig, reverse: bool) -> bool:
    """Rule 5: some sensor facing the way of travel has no fresh reading (or none exist)."""
    facing = [r for r in state.ranges if _faces(r, reverse)]
    return not facing or any(now_ns - r.t_ns > config.sonar_stale_ns for r in facing)


def _nearest_ahead(points: list[tuple[float, float]], v_m_s: float, omega_rad_s: float,
                   body_m: float, half_m: float, reverse: bool) -> float:
    """Rule 2: the distance from the body's end to the nearest echo in the swept corridor
    of half-width ``half_m``, m (0 when one is at or inside the end, inf when the corridor
    is empty)."""
    sign = -1.0 if reverse else 1.0
    curvature = omega_rad_s / v_m_s if v_m_s * sign > 1e-6 else 0.0
    nearest = math.inf
    for px, py in points:
        x = px * sign  # mirrored when reversing: the curvature keeps its sign
        s, lateral = _arc_coordinates(x, py, curvature)
        if s > 0 and abs(lateral) <= half_m:
            nearest = min(nearest, max(0.0, s - body_m))
    return nearest


def _nearest_doubtful(points: list[tuple[float, float]], arcs: list[np.ndarray | None],
                      odom_pose: tuple[float, float, float], v_m_s: float,
                      omega_rad_s: float, body_m: float, stop_half_m: float,
                      half_m: float) -> float:
    """Rule 3's creep: the distance from the front to the nearest echo placed in the
    forward corridor's margin (beyond ``stop_half_m`` from its middle, within ``half_m``)
    that may lie within ``stop_half_m`` after all: a point of its arc no reading saw free
    (``arcs``, odometry frame; the robot at ``odom_pose``) is in the inner band ahead, or
    where it lies is not known (None), m (inf when none). Only the arcs of echoes in the
    margin are turned into the robot frame."""
    curvature = omega_rad_s / v_m_s if v_m_s > 1e-6 else 0.0
    x0, y0, yaw = odom_pose
    c0, s0 = math.cos(yaw), math.sin(yaw)
    nearest = math.inf
    for (px, py), arc in zip(points, arcs, strict=True):
        s, lateral = _arc_coordinates(px, py, curvature)
        if s <= 0 or not stop_half_m < abs(lateral) <= half_m or s - body_m >= nearest:
            continue
        if arc is None or any(
                t > 0 and abs(side) <= stop_half_m
                for t, side in (_arc_coordinates(c0 * (x - x0) + s0 * (y - y0),
                                                 -s0 * (x - x0) + c0 * (y - y0), curvature)
                                for x, y in arc.tolist())):
            nearest = max(0.0, s - body_m)
    return nearest


def _arc_coordinates(x: float, y: float, curvature: float) -> tuple[float, float]:
    """A point's arc length along the path of curvature ``curvature`` (1/m) from the
    robot (forward positive) and its distance from that path, m."""
    if abs(curvature) < 1e-3:
        return x, y
    radius = 1.0 / curvature  # the centre of the turn at (0, radius)
    dx, dy = x, y - radius
    rho = math.hypot(dx, dy)
    # angle swept from the robot (at angle -pi/2 seen from a left turn's centre)
    angle = math.atan2(dx, -dy) if radius > 0 else math.atan2(dx, dy)
    return abs(radius) * angle, abs(radius) - rho


def _too_close_to_turn(points: list[tuple[float, float]], config: SafetyConfig) -> bool:
    """Rule 6: an echo inside the circle the robot's corners sweep turning in place."""
    reach = math.hypot(max(config.front_m, config.rear_m), config.half_width_m)
    limit = reach + config.turn_margin_m
    return any(math.hypot(px, py) < limit for px, py in points)


def _speed_ratio(distance_m: float, config: SafetyConfig) -> float:
    """Rule 3 short of the stop line: the fraction of the command allowed."""
    if distance_m >= config.slow_distance_m:
        return 1.0
    ramp = (distance_m - config.stop_distance_m) / (
        config.slow_distance_m - config.stop_distance_m)
    return max(config.min_speed_ratio, min(1.0, ramp))
