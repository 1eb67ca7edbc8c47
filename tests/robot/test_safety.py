"""Tests of robot/safety.py: the safety layer's rules, on P3-AT sonar geometry."""

from __future__ import annotations

import dataclasses
import math

import pytest

from robot.config import SafetyConfig
from robot.safety import SafetyGovernor
from shared.aria.p3at import SONAR_POSES
from shared.clock import ns_from_s
from shared.interfaces import BaseState, RangeReading
from shared.pose import Pose2

CONFIG = SafetyConfig()
FRONT_CENTRE = 3  # the front array's sonar at +10 deg, 245 mm ahead of the centre
NOTHING_M = 5.0  # the P3's maximum range: no echo
ORIGIN = Pose2(0.0, 0.0, 0.0)


def state(ranges: dict[int, float] | None = None, *, t_ns: int = 0,
          at: Pose2 = ORIGIN, read_at: Pose2 | None = None,
          bumped: bool = False, rear_only: bool = False,
          read_ns: int | None = None) -> BaseState:
    """The base at ``at`` (odometry frame) whose 16 sonars read ``ranges`` (default: no
    echo), taken at ``read_ns`` (default ``t_ns``) from ``read_at`` (default ``at``)."""
    ranges = ranges or {}
    readings = tuple(
        RangeReading(k, pose, ranges.get(k, NOTHING_M), t_ns if read_ns is None else read_ns,
                     at if read_at is None else read_at)
        for k, pose in enumerate(SONAR_POSES))
    return BaseState(at, 0.0, bumped, False, 13.0, True, ranges=readings,
                     bumped_rear_only=rear_only)


def echo_ahead(distance_m: float) -> dict[int, float]:
    """The front-centre sonar's range whose echo lies ``distance_m`` ahead of the front."""
    x, _, heading = SONAR_POSES[FRONT_CENTRE]
    return {FRONT_CENTRE: (CONFIG.front_m + distance_m - x) / math.cos(heading)}


class TestForward:
    def test_a_clear_way_passes_the_command(self) -> None:
        a = SafetyGovernor(CONFIG).assess(0, state(), 0.3, 0.1)
        assert (a.v_m_s, a.omega_rad_s, a.blocked) == (0.3, 0.1, None)

    def test_an_echo_inside_the_stop_line_stops_forward_motion(self) -> None:
        a = SafetyGovernor(CONFIG).assess(0, state(echo_ahead(0.35)), 0.2, 0.0)
        assert a.v_m_s == 0.0 and a.blocked is not None and a.blocked.cause == "obstacle"
        assert a.blocked.distance_m == pytest.approx(0.35)
        turning = SafetyGovernor(CONFIG).assess(0, state(echo_ahead(0.35)), 0.2, 0.05)
        assert turning.v_m_s == 0.0 and turning.omega_rad_s == 0.05  # in place: allowed
        assert a.blocked.describe() == "obstacle 0.35 m ahead"

    def test_nearer_echoes_slow_the_robot_down_on_the_same_arc(self) -> None:
        governor = SafetyGovernor(CONFIG)
        a = governor.assess(0, state(echo_ahead(0.8)), 0.2, 0.0)
        ratio = (0.8 - CONFIG.stop_distance_m) / (CONFIG.slow_distance_m - CONFIG.stop_distance_m)
        assert a.v_m_s == pytest.approx(0.2 * ratio) and a.blocked is None
        arc = governor.assess(0, state(echo_ahead(0.8)), 0.2, 0.02)
        assert arc.v_m_s < 0.2 and arc.omega_rad_s / arc.v_m_s == pytest.approx(0.02 / 0.2)
        near = SafetyGovernor(CONFIG).assess(0, state(echo_ahead(0.42)), 0.2, 0.0)
        assert near.v_m_s == pytest.approx(0.2 * CONFIG.min_speed_ratio)

    def test_a_person_walking_at_the_robot_stops_it_where_they_will_be(self) -> None:
        governor = SafetyGovernor(CONFIG)
        ring_ns = ns_from_s(0.32)  # the same sonar fires again
        for ping, ahead_m in enumerate((1.12, 0.8)):  # 1 m/s towards the robot
            first = governor.assess(ping * ring_ns, state(echo_ahead(ahead_m),
                                                          t_ns=ping * ring_ns), 0.2, 0.0)
            assert first.ahead_m == pytest.approx(ahead_m)  # one step is not yet a walk
        walking = governor.assess(2 * ring_ns, state(echo_ahead(0.48), t_ns=2 * ring_ns),
                                  0.2, 0.0)
        # counted 1 s on (approach_horizon_ns): at the front
        assert walking.v_m_s == 0.0 and walking.ahead_m == 0.0
        assert walking.blocked is not None and walking.blocked.cause == "obstacle"
        still = SafetyGovernor(CONFIG).assess(0, state(echo_ahead(0.48)), 0.2, 0.0)
        assert still.v_m_s > 0.0 and still.ahead_m == pytest.approx(0.48)

    def test_a_still_echo_does_not_approach_while_the_robot_drives_at_it(self) -> None:
        governor = SafetyGovernor(CONFIG)
        ring_ns = ns_from_s(0.32)
        governor.assess(0, state(echo_ahead(1.0)), 0.2, 0.0)
        driven = Pose2(0.2 * 0.32, 0.0, 0.0)
        a = governor.assess(ring_ns, state(echo_ahead(1.0 - driven.x_m), t_ns=ring_ns,
                                           at=driven), 0.2, 0.0)
        assert a.ahead_m == pytest.approx(1.0 - driven.x_m) and a.v_m_s > 0.0

    @pytest.mark.parametrize("ranges_m", [
        (4.0, 2.0, 0.5),  # the beam swept onto nearer surfaces: beyond approach_gate_m
        (1.0, 1.0, 0.6),  # one step: the beam found a person standing before the wall
        (1.0, 0.9, 0.8),  # 0.31 m/s: below approach_min_m_s (noise, an oblique wall)
    ])
    def test_a_jump_or_a_slow_drift_is_not_someone_coming(
            self, ranges_m: tuple[float, ...]) -> None:
        governor = SafetyGovernor(CONFIG)
        ring_ns = ns_from_s(0.32)
        for ping, ahead_m in enumerate(ranges_m):
            a = governor.assess(ping * ring_ns, state(echo_ahead(ahead_m),
                                                      t_ns=ping * ring_ns), 0.2, 0.0)
        assert a.ahead_m == pytest.approx(ranges_m[-1])

    def test_an_echo_beside_the_corridor_is_passed(self) -> None:
        side = {1: 0.6}  # the +50 deg sonar: the echo is 0.65 m to the left
        a = SafetyGovernor(CONFIG).assess(0, state(side), 0.2, 0.0)
        assert a.v_m_s == 0.2 and a.ahead_m == math.inf

    #: Stopping for the inner 3 cm of the margin only (the default), and for all of it.
    INNER = dataclasses.replace(CONFIG, side_stop_margin_m=0.03)
    WHOLE = dataclasses.replace(CONFIG, side_stop_margin_m=CONFIG.side_margin_m)

    def test_the_default_stops_for_the_inner_3_cm_of_the_margin(self) -> None:
        assert CONFIG == self.INNER

    def test_an_echo_in_the_corridors_margin_only_slows_the_robot(self) -> None:
        # the +30 deg sonar at 0.5 m: on its axis 0.35 m ahead, 0.33 m left: in the margin
        # (the robot's half width 0.2525 m + 0.03 m stops it, + 0.1 m slows it); 0.45 m
        # back the +10 deg sonar saw nothing through the inner part of its arc (15 to 22.5
        # degrees, within 3 cm of the robot's side), but not through the axis point
        back = Pose2(-0.45, 0.0, 0.0)
        x, y, heading = SONAR_POSES[2]
        axis = (x + 0.5 * math.cos(heading), y + 0.5 * math.sin(heading))
        before = state({2: math.hypot(axis[0] - x - back.x_m, axis[1] - y)}, at=back)
        t = ns_from_s(1.0)
        for config, creeps in ((self.INNER, True), (self.WHOLE, False)):
            governor = SafetyGovernor(config)
            governor.assess(0, before, 0.2, 0.0)
            a = governor.assess(t, state({2: 0.5}, t_ns=t), 0.2, 0.0)
            assert (a.blocked is None) is creeps
            if creeps:
                assert a.ahead_m == math.inf
                assert a.v_m_s == pytest.approx(0.2 * CONFIG.min_speed_ratio)

    def test_an_echo_in_the_margin_that_may_lie_nearer_stops_the_robot(self) -> None:
        # the same echo, with no reading before it: its arc reaches 15 degrees, within 3 cm
        # of the robot's side, and nothing says it is not there
        a = SafetyGovernor(self.INNER).assess(0, state({2: 0.5}), 0.2, 0.0)
        assert a.blocked is not None and a.ahead_m == pytest.approx(0.347, abs=0.005)

    def test_an_echo_coming_towards_the_robot_in_the_margin_is_not_crept_past(self) -> None:
        # the first test's echo, its object coming 4 cm nearer per half second as the
        # robot drives up: slow, but coming (approach_min_m_s 0.05 m/s here), and counted
        # where it is now (no horizon), in the margin: it may be anywhere ahead next
        x, y, heading = SONAR_POSES[2]
        axis = (x + 0.5 * math.cos(heading), y + 0.5 * math.sin(heading))
        for approach_min, creeps in ((CONFIG.approach_min_m_s, True), (0.05, False)):
            config = dataclasses.replace(self.INNER, approach_min_m_s=approach_min,
                                         approach_horizon_ns=0)
            governor = SafetyGovernor(config)
            for k, (back_m, nearer_m) in enumerate(((-0.45, 0.08), (-0.225, 0.04), (0.0, 0.0))):
                t = ns_from_s(0.5 * k)
                range_m = math.hypot(axis[0] - x - back_m, axis[1] - y) + nearer_m
                a = governor.assess(t, state({2: range_m}, t_ns=t, at=Pose2(back_m, 0.0, 0.0)),
                                    0.2, 0.0)
            assert (a.blocked is None) is creeps, approach_min

    def test_an_echo_within_the_stop_margin_stops_the_robot(self) -> None:
        # the +10 deg sonar at 0.45 m: 0.69 m ahead of the centre (0.37 m ahead of the
        # front), 0.10 m left
        a = SafetyGovernor(self.INNER).assess(0, state({3: 0.45}), 0.2, 0.0)
        narrow = dataclasses.replace(CONFIG, side_stop_margin_m=0.0, side_margin_m=0.0)
        assert a.blocked is not None and a.v_m_s == 0.0
        assert SafetyGovernor(narrow).assess(0, state({3: 0.45}), 0.2, 0.0).blocked is not None

    def test_the_corridor_follows_the_arc_of_the_command(self) -> None:
        left = {1: 0.3}  # ahead and to the left: (0.39, 0.35) m
        turning_left = SafetyGovernor(CONFIG).assess(0, state(left), 0.2, 0.4)  # R = 0.5 m
        assert turning_left.blocked is not None
        turning_right = SafetyGovernor(CONFIG).assess(0, state(left), 0.2, -0.4)
        assert turning_right.blocked is None and turning_right.v_m_s == 0.2

    def test_an_echo_stays_where_it_was_while_the_robot_drives_on(self) -> None:
        moved = state(echo_ahead(0.85), at=Pose2(0.5, 0.0, 0.0), read_at=Pose2(0.0, 0.0, 0.0))
        a = SafetyGovernor(CONFIG).assess(0, moved, 0.2, 0.0)
        assert a.ahead_m == pytest.approx(0.35) and a.v_m_s == 0.0


class TestArcs:
    """Rule 1's placement on the arc: the +30 deg sonar (2) reads 0.5 m. On its axis the echo
    is 0.35 m ahead of the front, 0.33 m left (inside the corridor's 0.35 m): a stop. The
    object is at the cone's left edge (45 deg), 0.43 m left: beside the corridor. With one
    band (an echo anywhere in the corridor stops the robot, the default), so that where the
    echo goes decides whether the robot stops."""

    ONE_BAND = dataclasses.replace(CONFIG, side_stop_margin_m=CONFIG.side_margin_m)

    EDGE = (SONAR_POSES[2].x_m + 0.5 * math.cos(math.radians(45.0)),
            SONAR_POSES[2].y_m + 0.5 * math.sin(math.radians(45.0)))
    BACK = Pose2(-0.55, 0.0, 0.0)  # where the robot stood a second before

    def range_from_back(self) -> float:
        x, y, _ = SONAR_POSES[2]
        return math.hypot(self.EDGE[0] - (x + self.BACK.x_m), self.EDGE[1] - y)

    def test_on_its_axis_the_echo_stops_the_robot(self) -> None:
        a = SafetyGovernor(self.ONE_BAND).assess(0, state({2: 0.5}), 0.2, 0.0)
        assert a.blocked is not None and a.ahead_m == pytest.approx(0.347, abs=0.005)

    def test_a_still_object_goes_where_the_neighbours_saw_nothing(self) -> None:
        governor = SafetyGovernor(self.ONE_BAND)
        # 0.55 m back, the +10 deg sonar (3) saw nothing through the axis point, and the
        # +30 deg one already saw the object (its range shrank by less than the way driven)
        governor.assess(0, state({2: self.range_from_back()}, at=self.BACK), 0.2, 0.0)
        t = ns_from_s(1.0)
        a = governor.assess(t, state({2: 0.5}, t_ns=t), 0.2, 0.0)
        assert a.blocked is None and a.v_m_s == 0.2 and a.ahead_m == math.inf

    def test_a_new_echo_is_not_placed_by_what_the_sonars_saw_before_it(self) -> None:
        governor = SafetyGovernor(self.ONE_BAND)
        governor.assess(0, state(at=self.BACK), 0.2, 0.0)  # nothing then: it came since
        t = ns_from_s(1.0)
        a = governor.assess(t, state({2: 0.5}, t_ns=t), 0.2, 0.0)
        assert a.blocked is not None and a.ahead_m == pytest.approx(0.347, abs=0.005)

    def test_reversing_places_the_echoes_behind_not_those_ahead(self) -> None:
        # the front +10 deg and the rear -170 deg sonars (3 and 11) read 1 m at the same
        # time: driving forward places the first, reversing the second (0.9 m behind)
        both = state({3: 1.0, 11: 1.0})
        governor = SafetyGovernor(self.ONE_BAND)
        governor.assess(0, both, 0.2, 0.0)
        backing = governor.assess(0, both, -0.2, 0.0)
        alone = SafetyGovernor(self.ONE_BAND).assess(0, both, -0.2, 0.0)
        assert backing.v_m_s == alone.v_m_s and -0.2 < backing.v_m_s < 0.0

    def test_readings_from_too_far_back_are_forgotten(self) -> None:
        far = dataclasses.replace(self.ONE_BAND, carve_distance_m=0.3)
        governor = SafetyGovernor(far)
        governor.assess(0, state({2: self.range_from_back()}, at=self.BACK), 0.2, 0.0)
        t = ns_from_s(1.0)
        assert governor.assess(t, state({2: 0.5}, t_ns=t), 0.2, 0.0).blocked is not None


class TestHysteresis:
    def test_the_way_clears_after_the_margin_and_the_dwell(self) -> None:
        governor = SafetyGovernor(CONFIG)
        assert governor.assess(0, state(echo_ahead(0.3)), 0.2, 0.0).blocked is not None
        inside = CONFIG.stop_distance_m + CONFIG.clear_margin_m - 0.01
        t = ns_from_s(0.5)
        assert governor.assess(t, state(echo_ahead(inside), t_ns=t), 0.2, 0.0).v_m_s == 0.0
        t = ns_from_s(1.0)
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).blocked is not None  # clear: dwell
        t += CONFIG.clear_dwell_ns - 1
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).blocked is not None
        t += 1
        a = governor.assess(t, state(t_ns=t), 0.2, 0.0)
        assert a.blocked is None and a.v_m_s == 0.2

    def test_an_echo_returning_during_the_dwell_restarts_it(self) -> None:
        governor = SafetyGovernor(CONFIG)
        governor.assess(0, state(echo_ahead(0.3)), 0.0, 0.0)
        governor.assess(ns_from_s(0.2), state(t_ns=ns_from_s(0.2)), 0.0, 0.0)
        t = ns_from_s(0.9)
        governor.assess(t, state(echo_ahead(0.45), t_ns=t), 0.0, 0.0)
        t = ns_from_s(1.5)
        assert governor.assess(t, state(t_ns=t), 0.0, 0.0).blocked is not None


class TestSilence:
    def test_stale_front_readings_are_not_clear(self) -> None:
        stale = state(t_ns=ns_from_s(5.0), read_ns=ns_from_s(3.0))
        a = SafetyGovernor(CONFIG).assess(ns_from_s(5.0), stale, 0.2, 0.0)
        assert a.v_m_s == 0.0 and a.blocked is not None and a.blocked.cause == "sonar_silent"

    def test_a_base_without_sonars_cannot_drive_forward(self) -> None:
        bare = BaseState(Pose2(0.0, 0.0, 0.0), 0.0, False, False, 13.0, True)
        a = SafetyGovernor(CONFIG).assess(0, bare, 0.2, 0.0)
        assert a.v_m_s == 0.0 and a.blocked is not None and a.blocked.cause == "sonar_silent"

    def test_one_silent_front_sonar_is_enough(self) -> None:
        base = state(t_ns=ns_from_s(5.0))
        readings = list(base.ranges)
        readings[FRONT_CENTRE] = RangeReading(FRONT_CENTRE, SONAR_POSES[FRONT_CENTRE], 5.0,
                                              ns_from_s(3.0), Pose2(0.0, 0.0, 0.0))
        silent = BaseState(base.odom_pose, 0.0, False, False, 13.0, True, ranges=tuple(readings))
        assert SafetyGovernor(CONFIG).assess(ns_from_s(5.0), silent, 0.2, 0.0).v_m_s == 0.0


class TestTurningAndReversing:
    def test_turning_in_place_is_refused_with_an_echo_inside_the_swept_circle(self) -> None:
        close = {0: 0.2}  # the left sonar: an echo 0.34 m left of the centre
        a = SafetyGovernor(CONFIG).assess(0, state(close), 0.0, 0.5)
        assert a.omega_rad_s == 0.0
        assert SafetyGovernor(CONFIG).assess(0, state({0: 0.6}), 0.0, 0.5).omega_rad_s == 0.5

    def test_reversing_watches_the_rear_sonars(self) -> None:
        behind = {11: 0.2}  # the rear array's -170 deg sonar
        a = SafetyGovernor(CONFIG).assess(0, state(behind), -0.2, 0.0)
        assert a.v_m_s == 0.0
        blocked_ahead = SafetyGovernor(CONFIG).assess(0, state(echo_ahead(0.2)), -0.2, 0.0)
        assert blocked_ahead.v_m_s == -0.2  # backing away from an obstacle is allowed


class TestHolds:
    def test_a_bumper_hit_stops_and_holds_until_released(self) -> None:
        governor = SafetyGovernor(CONFIG)
        assert governor.assess(0, state(), 0.2, 0.0).v_m_s == 0.2  # driving
        hit = governor.assess(0, state(bumped=True), 0.2, 0.3)
        assert (hit.v_m_s, hit.omega_rad_s, hit.blocked.cause) == (0.0, 0.0, "bumper")
        assert governor.assess(1, state(t_ns=1), 0.2, 0.0).v_m_s == 0.0  # released bumper
        governor.release()
        assert governor.assess(2, state(t_ns=2), 0.2, 0.0).v_m_s == 0.2

    def test_someone_walking_into_a_robot_that_stands_is_a_wait_not_a_hold(self) -> None:
        governor = SafetyGovernor(CONFIG)
        governor.assess(0, state(), 0.2, 0.0)  # drove until t = 0, then stood
        t = ns_from_s(1.0)
        pushed = governor.assess(t, state(bumped=True, t_ns=t), 0.2, 0.3)
        assert (pushed.v_m_s, pushed.omega_rad_s, pushed.blocked.cause) == (0.0, 0.0, "pushed")
        assert governor.latched is None
        t = ns_from_s(1.5)  # released: the way must stay clear for the dwell
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).v_m_s == 0.0
        t += CONFIG.clear_dwell_ns
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).v_m_s == 0.2

    def test_someone_walking_into_the_back_of_a_robot_driving_away_is_a_wait(self) -> None:
        governor = SafetyGovernor(CONFIG)
        governor.assess(0, state(), 0.2, 0.03)  # forward on a gentle arc, as on a route
        pushed = governor.assess(1, state(bumped=True, rear_only=True, t_ns=1), 0.2, 0.03)
        assert (pushed.v_m_s, pushed.blocked.cause) == (0.0, "pushed")
        assert governor.latched is None
        t = ns_from_s(0.2)  # released: the way must stay clear for the dwell
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).v_m_s == 0.0
        t += CONFIG.clear_dwell_ns
        assert governor.assess(t, state(t_ns=t), 0.2, 0.0).v_m_s == 0.2

    @pytest.mark.parametrize(("v_m_s", "omega_rad_s"), [
        (-0.2, 0.0),  # reversing into it
        (0.2, 0.3),  # the rear corners swing sideways at 9 cm/s
        (0.0, 0.2),  # turning in place
    ])
    def test_the_rear_bumper_is_a_hit_when_the_rear_moved_into_the_world(
            self, v_m_s: float, omega_rad_s: float) -> None:
        governor = SafetyGovernor(CONFIG)
        assert governor.assess(0, state(), v_m_s, omega_rad_s).v_m_s == v_m_s
        t = ns_from_s(0.3)  # braking still, within MOVING_GRACE_NS
        hit = governor.assess(t, state(bumped=True, rear_only=True, t_ns=t), 0.0, 0.0)
        assert hit.blocked.cause == "bumper" and governor.latched is not None

    def test_the_emergency_stop_holds_until_released(self) -> None:
        governor = SafetyGovernor(CONFIG)
        governor.emergency_stop(5)
        a = governor.assess(6, state(t_ns=6), 0.2, 0.3)
        assert (a.v_m_s, a.omega_rad_s) == (0.0, 0.0)
        assert a.blocked is not None and (a.blocked.cause, a.blocked.since_ns) == ("e_stop", 5)
        governor.release()
        assert governor.assess(7, state(t_ns=7), 0.2, 0.3).v_m_s == 0.2


class TestConfig:
    @pytest.mark.parametrize(("changes", "problem"), [
        ({"stop_distance_m": 0.0}, "stop_distance_m must be > 0"),
        ({"slow_distance_m": 0.3}, "slow_distance_m must be > stop_distance_m"),
        ({"min_speed_ratio": 0.0}, "min_speed_ratio must be in"),
        ({"clear_dwell_ns": -1}, "clear_dwell_ns must be >= 0"),
        ({"clear_width_rad": 0.6}, "clear_width_rad must be <= beam_width_rad"),
    ])
    def test_bad_values_are_refused(self, changes: dict[str, float], problem: str) -> None:
        with pytest.raises(ValueError, match=problem):
            SafetyConfig(**changes)
