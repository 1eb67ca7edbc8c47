"""Tests of robot/control_law.py: eq. (2) of Courbon et al. 2008, its gains and bound."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.config import ControlConfig
from robot.control_law import Twist, gains, settling_distance_m, steer
from shared.errors import DegenerateGeometryError

FRAME_RATE_HZ = 15.0
DT_S = 1.0 / FRAME_RATE_HZ


def distance_pole(g_1_m: float, law: str = "paper") -> ControlConfig:
    return ControlConfig(double_pole=g_1_m, pole_domain="distance", law=law)


def drive(x: float, y: float, yaw: float, v: float, omega: float) -> tuple[float, float, float]:
    """Exact unicycle motion over one frame at constant (v, omega)."""
    if abs(omega) < 1e-12:
        return x + v * DT_S * math.cos(yaw), y + v * DT_S * math.sin(yaw), yaw
    new_yaw = yaw + omega * DT_S
    return (x + v / omega * (math.sin(new_yaw) - math.sin(yaw)),
            y - v / omega * (math.cos(new_yaw) - math.cos(yaw)), new_yaw)


@dataclass(frozen=True)
class Run:
    distance_m: tuple[float, ...]
    y_m: tuple[float, ...]
    omega_rad_s: tuple[float, ...]

    def settled_at_m(self, tolerance_m: float) -> float:
        """Distance after which |y| stays below the tolerance."""
        outside = [d for d, y in zip(self.distance_m, self.y_m, strict=True)
                   if abs(y) >= tolerance_m]
        return outside[-1] if outside else 0.0


def follow_line(config: ControlConfig, y0_m: float, length_m: float, scale: float = 1.0) -> Run:
    """The reference's closed-loop simulation (visual-navigation.md sec. 1.2): a straight
    line along x, 15 Hz, one frame of delay, measured y scaled by ``scale``."""
    x, y, yaw = 0.0, y0_m, 0.0
    pending = deque([0.0])
    travelled, distances, ys, omegas = 0.0, [], [], []
    while travelled < length_m:
        twist = steer(scale * y, yaw, config)
        pending.append(twist.omega_rad_s)
        omega = pending.popleft()
        x, y, yaw = drive(x, y, yaw, twist.v_m_s, omega)
        travelled += twist.v_m_s * DT_S
        distances.append(travelled)
        ys.append(y)
        omegas.append(omega)
    return Run(tuple(distances), tuple(ys), tuple(omegas))


class TestGains:
    def test_double_pole_in_distance(self) -> None:
        assert gains(distance_pole(0.3)) == pytest.approx((0.09, 0.6))

    def test_default_reads_the_pole_in_time(self) -> None:
        config = ControlConfig()
        assert config.pole_1_m == pytest.approx(0.3 / 0.2)
        assert gains(config) == pytest.approx((2.25, 3.0))


class TestSteer:
    def test_known_answer(self) -> None:
        y, theta = 0.1, 0.05
        kp, kd = 1.0, 2.0  # g = 1 1/m
        v_cos3 = 0.2 * math.cos(theta) ** 3
        expected = -v_cos3 * kp * y - abs(v_cos3) * kd * math.tan(theta)
        twist = steer(y, theta, distance_pole(1.0))
        assert twist == Twist(v_m_s=0.2, omega_rad_s=pytest.approx(expected, rel=1e-12))
        assert twist.omega_rad_s == pytest.approx(-0.0398668, abs=1e-7)  # by hand

    def test_on_the_line_goes_straight(self) -> None:
        assert steer(0.0, 0.0, ControlConfig()) == Twist(0.2, 0.0)

    def test_turns_back_towards_the_line(self) -> None:
        assert steer(0.05, 0.0, ControlConfig()).omega_rad_s < 0  # left of it: turn right
        assert steer(0.0, -0.05, ControlConfig()).omega_rad_s > 0  # heading right: turn left

    def test_saturates_at_the_bound(self) -> None:
        config = ControlConfig()
        assert steer(2.0, 0.0, config).omega_rad_s == -config.max_omega_rad_s
        assert steer(-2.0, 0.0, config).omega_rad_s == config.max_omega_rad_s
        assert config.max_omega_rad_s == pytest.approx(math.radians(25))

    @given(y=st.floats(-5, 5), theta=st.floats(-math.pi, math.pi),
           c=st.floats(-3, 3), law=st.sampled_from(["paper", "paper+ff"]))
    def test_never_exceeds_the_bound(self, y: float, theta: float, c: float, law: str) -> None:
        config = ControlConfig(law=law)
        if law == "paper+ff" and 1 - c * y <= 0:
            return
        assert abs(steer(y, theta, config, c).omega_rad_s) <= config.max_omega_rad_s

    @given(y=st.floats(-1, 1), theta=st.floats(-1.5, 1.5), c=st.floats(-2, 2))
    def test_mirror_symmetry(self, y: float, theta: float, c: float) -> None:
        config = ControlConfig(law="paper+ff", max_omega_rad_s=100.0)
        if 1 - c * y <= 0:
            return
        left, right = steer(y, theta, config, c), steer(-y, -theta, config, -c)
        assert right.omega_rad_s == pytest.approx(-left.omega_rad_s, abs=1e-12)

    def test_feed_forward_on_the_arc_is_v_times_curvature(self) -> None:
        twist = steer(0.0, 0.0, ControlConfig(law="paper+ff"), curvature_ff_1_m=0.5)
        assert twist.omega_rad_s == pytest.approx(0.2 * 0.5)

    def test_paper_law_ignores_the_curvature(self) -> None:
        assert steer(0.0, 0.0, ControlConfig(law="paper"), curvature_ff_1_m=0.5).omega_rad_s == 0.0

    def test_degenerate_beyond_the_arc_centre(self) -> None:
        with pytest.raises(DegenerateGeometryError, match="centre of the reference arc"):
            steer(2.5, 0.0, ControlConfig(law="paper+ff"), curvature_ff_1_m=0.5)

    @pytest.mark.parametrize("bad", [math.nan, math.inf])
    def test_non_finite_input(self, bad: float) -> None:
        with pytest.raises(ValueError, match="theta_rad must be finite"):
            steer(0.0, bad, ControlConfig())


class TestClosedLoop:
    # Reference visual-navigation.md sec. 1.2: (g 1/m, scale error, m to 5 cm, m to 1 cm,
    # overshoot m); V = 0.2 m/s, 10 deg/s, 15 Hz, one frame of delay, y0 = 0.3 m.
    @pytest.mark.parametrize(("g", "scale", "to_5cm", "to_1cm", "overshoot"), [
        (0.3, 1.0, 10.8, 17.4, 0.0),
        (0.3, 2.0, 5.6, 12.4, 0.013),
        (1.0, 1.0, 3.2, 5.2, 0.0),
        (1.0, 0.5, 6.7, 12.2, 0.0),
        (1.0, 2.0, 1.7, 3.7, 0.014),
    ])
    def test_reproduces_the_reference_table(
        self, g: float, scale: float, to_5cm: float, to_1cm: float, overshoot: float
    ) -> None:
        run = follow_line(distance_pole(g), 0.3, 20.0, scale)
        assert run.settled_at_m(0.05) == pytest.approx(to_5cm, rel=0.15)
        assert run.settled_at_m(0.01) == pytest.approx(to_1cm, rel=0.15)
        assert max(0.0, -min(run.y_m)) == pytest.approx(overshoot, abs=0.003)

    def test_half_scale_is_slow_for_the_paper_pole(self) -> None:
        assert follow_line(distance_pole(0.3), 0.3, 20.0, 0.5).settled_at_m(0.05) > 19.0

    def test_matches_the_linear_settling_distance(self) -> None:
        run = follow_line(distance_pole(1.0), 0.3, 8.0)
        for tolerance in (0.05, 0.01):
            assert run.settled_at_m(tolerance) == pytest.approx(
                settling_distance_m(1.0, 0.3, tolerance), rel=0.03)

    def test_default_gains_settle_within_three_metres(self) -> None:
        config = ControlConfig()
        run = follow_line(config, 0.3, 6.0)
        assert run.settled_at_m(0.05) == pytest.approx(
            settling_distance_m(config.pole_1_m, 0.3, 0.05), rel=0.1)
        assert run.settled_at_m(0.05) < 3.0
        assert max(abs(w) for w in run.omega_rad_s) <= config.max_omega_rad_s

    @pytest.mark.parametrize(("law", "expected_offset_m"), [
        ("paper+ff", 0.0),
        # eq. (2) alone on a circle settles where -Kp y = c / (1 - c y) (theta = 0):
        ("paper", (2.25 - math.sqrt(2.25**2 + 4 * 2.25 * 0.5**2)) / (2 * 2.25 * 0.5)),
    ])
    def test_on_a_circle(self, law: str, expected_offset_m: float) -> None:
        radius = 2.0  # c = 0.5 1/m, V c = 0.1 rad/s, inside the 10 deg/s bound
        config = ControlConfig(law=law)
        x, y, yaw = 0.0, 0.0, 0.0  # on the circle centred at (0, radius), heading along it
        for _ in range(int(25.0 / 0.2 / DT_S)):
            rx, ry = x, y - radius
            y_err = radius - math.hypot(rx, ry)
            theta = math.remainder(yaw - (math.atan2(ry, rx) + math.pi / 2), math.tau)
            twist = steer(y_err, theta, config, 1.0 / radius)
            x, y, yaw = drive(x, y, yaw, twist.v_m_s, twist.omega_rad_s)
        assert y_err == pytest.approx(expected_offset_m, abs=0.002)


class TestSettlingDistance:
    def test_known_answer(self) -> None:
        # y0 (1 + x) exp(-x) = tolerance at x = g s
        s = settling_distance_m(0.3, 0.3, 0.05)
        x = 0.3 * s
        assert 0.3 * (1 + x) * math.exp(-x) == pytest.approx(0.05, rel=1e-9)
        assert s == pytest.approx(10.78, abs=0.01)

    def test_inside_the_band_already(self) -> None:
        assert settling_distance_m(1.0, 0.01, 0.05) == 0.0
        assert settling_distance_m(1.0, 0.0, 0.05) == 0.0

    def test_sign_of_y0_does_not_matter(self) -> None:
        assert settling_distance_m(1.0, -0.3, 0.05) == settling_distance_m(1.0, 0.3, 0.05)

    def test_bad_arguments(self) -> None:
        with pytest.raises(ValueError, match="pole_1_m must be > 0"):
            settling_distance_m(0.0, 0.3, 0.05)
        with pytest.raises(ValueError, match="tolerance_m must be > 0"):
            settling_distance_m(1.0, 0.3, 0.0)
