from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from shared.pose import Pose2
from sim.body import ramp
from sim.config import BodyConfig, OdometryConfig, SimConfig
from sim.simulation import Simulation
from sim.world import World
from tests.sim.rooms import box_room

DT_S = 0.01
NO_ODOMETRY_ERRORS = OdometryConfig(
    trans_scale_sigma=0, rot_scale_sigma=0, trans_noise_m_s=0, rot_noise_rad_s=0
)


def room(start: Pose2 | None = None, size: tuple[float, float] = (10.0, 6.0)) -> World:
    """The 10 x 6 m test room, starting by default at (2, 3) facing +x."""
    return box_room(size, start or Pose2(2.0, 3.0, 0.0))


def make_sim(world: World | None = None, **config: object) -> Simulation:
    return Simulation(world or room(), SimConfig(landmark_density_scale=0.0, **config))  # type: ignore[arg-type]


def run(sim: Simulation, seconds: float) -> np.ndarray:
    """Step for ``seconds``; returns per-step rows (vx, vy, omega, x, y, yaw)."""
    rows = []
    for _ in range(round(seconds / DT_S)):
        sim.step()
        rows.append(sim.body.velocity_base + sim.body.pose_w)
    return np.array(rows)


class TestLimits:
    def test_speeds_up_and_slows_down_at_the_acceleration_limits(self) -> None:
        sim = make_sim()
        cfg = sim.config.body
        sim.body.command(0.5, 0.0)
        up = run(sim, 2.5)
        v = up[:, 0]
        assert np.all(np.diff(v) <= cfg.accel_m_s2 * DT_S + 1e-9)
        # A set-point moves the body one step later (after the contact solver).
        assert v[0] == 0.0
        assert v[1] == pytest.approx(cfg.accel_m_s2 * DT_S)
        reached = np.argmax(v >= 0.5 - 1e-9)
        assert reached == pytest.approx(0.5 / cfg.accel_m_s2 / DT_S, abs=1)
        assert v.max() == pytest.approx(0.5)
        sim.body.command(0.0, 0.0)
        down = run(sim, 1.5)[:, 0]
        assert np.all(np.diff(down) >= -cfg.decel_m_s2 * DT_S - 1e-9)
        assert np.argmax(down <= 1e-12) == pytest.approx(0.5 / cfg.decel_m_s2 / DT_S, abs=1)
        assert abs(down[-1]) < 1e-12

    def test_reversal_brakes_to_zero_then_accelerates(self) -> None:
        sim = make_sim(body=BodyConfig(accel_m_s2=0.2, decel_m_s2=1.0))
        sim.body.command(0.3, 0.0)
        run(sim, 2.0)
        sim.body.command(-0.3, 0.0)
        v = run(sim, 2.5)[:, 0]
        braking = v > 0
        assert np.allclose(
            np.diff(v[: braking.sum() + 1]), -1.0 * DT_S, atol=1e-9
        )  # decel limit down to 0
        reversing = np.diff(v[braking.sum() :])
        assert np.all(reversing >= -0.2 * DT_S - 1e-9)  # then the accel limit
        assert v[-1] == pytest.approx(-0.3)

    def test_commands_are_clamped_to_the_speed_limits(self) -> None:
        sim = make_sim()
        sim.body.command(5.0, -9.0)
        cfg = sim.config.body
        assert sim.body.commanded == (cfg.max_speed_m_s, -cfg.max_omega_rad_s)
        sim.body.place(Pose2(5.0, 3.0, 0.0))
        sim.body.command(0.0, 9.0)
        w = run(sim, 3.0)[:, 2]
        assert np.all(np.diff(w) <= cfg.rot_accel_rad_s2 * DT_S + 1e-9)
        assert w.max() == pytest.approx(cfg.max_omega_rad_s)

    def test_non_finite_command_is_refused(self) -> None:
        with pytest.raises(ValueError, match="finite"):
            make_sim().body.command(math.nan, 0.0)

    def test_unicycle_motion_has_no_lateral_slide(self) -> None:
        sim = make_sim(world=room(Pose2(5.0, 2.0, 0.0)))
        sim.body.command(0.4, 0.4)
        rows = run(sim, 8.0)
        assert np.abs(rows[:, 1]).max() < 1e-9
        # After the ramp, a circle of radius v / omega = 1 m: a fixed centre of curvature.
        late = rows[300:]
        centre_x = late[:, 3] - np.sin(late[:, 5])
        centre_y = late[:, 4] + np.cos(late[:, 5])
        assert np.ptp(centre_x) < 0.01 and np.ptp(centre_y) < 0.01


class TestWalls:
    def test_driving_into_a_wall_bumps_stalls_and_stops_at_the_wall(self) -> None:
        sim = make_sim(odometry=NO_ODOMETRY_ERRORS)
        cfg = sim.config.body
        sim.body.command(0.5, 0.0)
        rows = run(sim, 20.0)
        contact_x = 10.0 - 0.05 - cfg.length_m / 2
        assert rows[-1, 3] == pytest.approx(contact_x, abs=0.01)
        assert rows[:, 3].max() < contact_x + 0.01
        assert sim.body.bumped_front and not sim.body.bumped_rear
        assert sim.body.stalled
        # The wheels stall too: odometry stops where the robot stopped.
        odom_x = sim.body.odom_pose[0]
        run(sim, 1.0)
        assert sim.body.odom_pose[0] == pytest.approx(odom_x, abs=1e-6)
        assert sim.body.odom_pose[0] == pytest.approx(sim.body.pose_w[0] - 2.0, abs=1e-6)

    def test_stall_is_reported_stall_time_after_the_robot_is_blocked(self) -> None:
        sim = make_sim(world=room(Pose2(9.4, 3.0, 0.0)))
        sim.body.command(0.3, 0.0)
        bumped, stalled = [], []
        for _ in range(300):
            sim.step()
            bumped.append(sim.body.bumped_front)
            stalled.append(sim.body.stalled)
        steps = stalled.index(True) - bumped.index(True)
        assert steps * DT_S == pytest.approx(sim.config.body.stall_time_s, abs=2.5 * DT_S)
        sim.body.command(0.0, 0.0)
        sim.step()
        assert not sim.body.stalled

    def test_reversing_into_a_wall_bumps_the_rear(self) -> None:
        sim = make_sim(world=room(Pose2(1.0, 3.0, 0.0)))
        sim.body.command(-0.3, 0.0)
        run(sim, 3.0)
        assert sim.body.bumped_rear and not sim.body.bumped_front


START = Pose2(10.0, 10.0, math.radians(30.0))


class TestOdometry:
    @staticmethod
    def drive(sim: Simulation) -> None:
        for v, w, seconds in ((0.5, 0.0, 4.0), (0.4, 0.5, 6.0), (0.6, -0.3, 5.0), (0.0, 0.0, 2.0)):
            sim.body.command(v, w)
            run(sim, seconds)
            assert not (sim.body.bumped_front or sim.body.bumped_rear)

    def test_equals_truth_without_errors(self) -> None:
        sim = make_sim(world=room(START, (20.0, 20.0)), odometry=NO_ODOMETRY_ERRORS)
        self.drive(sim)
        x, y, yaw = sim.body.pose_w
        c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
        dx, dy = x - START.x_m, y - START.y_m
        ox, oy, oyaw = sim.body.odom_pose
        assert (ox, oy) == pytest.approx((c * dx + s * dy, -s * dx + c * dy), abs=1e-9)
        assert math.remainder(oyaw - (yaw - math.radians(30.0)), 2 * math.pi) == pytest.approx(
            0.0, abs=1e-9
        )
        assert sim.body.odom_distance_m == pytest.approx(0.5 * 4.0 + 0.4 * 6.0 + 0.6 * 5.0, abs=0.2)

    def test_drifts_boundedly_with_errors(self) -> None:
        errors = OdometryConfig(
            trans_scale_sigma=0.02, rot_scale_sigma=0.03, trans_noise_m_s=0.01, rot_noise_rad_s=0.01
        )
        final_errors = []
        for seed in range(5):
            sim = make_sim(world=room(START, (20.0, 20.0)), odometry=errors, seed=seed)
            self.drive(sim)
            dx, dy = sim.body.pose_w[0] - START.x_m, sim.body.pose_w[1] - START.y_m
            c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
            truth = np.array([c * dx + s * dy, -s * dx + c * dy])
            final_errors.append(np.linalg.norm(np.array(sim.body.odom_pose[:2]) - truth))
        assert min(final_errors) > 1e-4  # the errors are there...
        assert max(final_errors) < 0.1 * 7.4  # ...but within 10 % of the 7.4 m driven
        assert len(set(final_errors)) == 5

    def test_no_noise_while_parked(self) -> None:
        sim = make_sim(odometry=OdometryConfig(trans_noise_m_s=1.0, rot_noise_rad_s=1.0))
        run(sim, 1.0)
        assert sim.body.odom_pose == (0.0, 0.0, 0.0)


class TestRamp:
    @settings(max_examples=200, deadline=None)
    @given(
        current=st.floats(-1.0, 1.0),
        target=st.floats(-1.0, 1.0),
        up=st.floats(0.0, 0.1),
        down=st.floats(0.0, 0.1),
    )
    @example(current=-5e-324, target=1.0, up=0.0, down=0.0625)  # found by the suite
    def test_moves_towards_the_target_within_the_limits(
        self, current: float, target: float, up: float, down: float
    ) -> None:
        nxt = ramp(current, target, up, down)
        assert min(current, target) - 1e-12 <= nxt <= max(current, target) + 1e-12  # no overshoot
        assert not (nxt < 0 < current or current < 0 < nxt)  # a reversal stops at zero first
        if abs(nxt) > abs(current):  # speeding up
            assert abs(nxt - current) <= up + 1e-12
        else:  # slowing down
            assert abs(nxt - current) <= down + 1e-12
