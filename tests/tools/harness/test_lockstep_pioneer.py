"""The demo's base: our ARIA driver on the emulated Pioneer over an in-memory pipe, lock-step."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import PioneerDriverConfig
from shared.interfaces import MobileBase
from shared.pose import Pose2
from sim.config import SimConfig
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import load_world
from tools.harness.lockstep_pioneer import lockstep_pioneer

#: How often the tests repeat a command, as the robot's loop does on every frame, ns.
REPEAT_NS = 100_000_000


def drive(base: MobileBase, clock: SimClock, v_m_s: float, omega_rad_s: float,
          until_ns: int) -> None:
    """Command ``v_m_s`` (m/s) and ``omega_rad_s`` (rad/s) every :data:`REPEAT_NS` of
    simulated time until ``until_ns``, as a control loop would."""
    while clock.now_ns() < until_ns:
        base.command(v_m_s, omega_rad_s)
        clock.sleep_until_ns(min(until_ns, clock.now_ns() + REPEAT_NS))


@pytest.fixture(scope="module")
def world():
    return load_world("lab")


@pytest.fixture
def clock(world) -> SimClock:
    return SimClock(Simulation(world, SimConfig(seed=3)))


def test_connects_with_the_motors_enabled_and_is_a_mobile_base(clock: SimClock) -> None:
    base, server = lockstep_pioneer(clock, PioneerDriverConfig(), np.random.default_rng(0))
    assert isinstance(base, MobileBase)
    assert base.state().motors_enabled and server.emulator.motors_enabled
    assert base.state().reporting
    assert clock.now_ns() < 1_000_000_000  # the handshake takes simulated time, not seconds


def test_commands_move_the_body_and_odometry_comes_back_in_sips(clock: SimClock) -> None:
    sim = clock.simulation
    sim.place_robot(Pose2(8.0, 10.0, 0.0))
    base, server = lockstep_pioneer(clock, PioneerDriverConfig(), np.random.default_rng(0))
    start = clock.now_ns()
    drive(base, clock, 0.3, 0.0, start + 2_000_000_000)
    state = base.state()
    assert 0.4 < state.odom_distance_m < 0.65
    assert 0.4 < state.odom_pose[0] < 0.65 and abs(state.odom_pose[1]) < 0.05
    assert sim.body.pose_w[0] - 8.0 == pytest.approx(state.odom_pose[0], abs=0.05)
    assert not state.bumped and not state.stalled and state.battery_v > 12.0
    base.stop()
    clock.sleep_until_ns(start + 4_000_000_000)
    travelled = base.state().odom_distance_m
    clock.sleep_until_ns(start + 5_000_000_000)
    assert base.state().odom_distance_m == pytest.approx(travelled, abs=1e-3)
    stats = server.emulator.stats
    assert stats.bad_checksums == 0 and stats.sips_sent >= 40


def test_a_cut_cable_makes_the_base_not_reporting_until_it_reconnects(clock: SimClock) -> None:
    config = PioneerDriverConfig()
    base, server = lockstep_pioneer(clock, config, np.random.default_rng(0))
    cut_ns = clock.now_ns()
    server.cut(10_000_000_000)  # longer than the link timeout: the driver gives it up
    clock.sleep_until_ns(cut_ns + config.report_timeout_ns - 200_000_000)
    assert base.state().reporting  # SIPs 100 ms apart: a few missed is not yet quiet
    clock.sleep_until_ns(cut_ns + config.report_timeout_ns + 200_000_000)
    assert not base.state().reporting
    clock.sleep_until_ns(cut_ns + 25_000_000_000)  # mended at 10 s, reconnect backoff
    assert base.state().reporting and base.state().motors_enabled


def test_driving_into_a_wall_bumps_or_stalls(clock: SimClock) -> None:
    # The corridor's north wall ahead.
    clock.simulation.place_robot(Pose2(8.0, 10.0, math.radians(90.0)))
    base, _ = lockstep_pioneer(clock, PioneerDriverConfig(), np.random.default_rng(0))
    start, seen = clock.now_ns(), False
    for k in range(1, 80):
        base.command(0.4, 0.0)
        clock.sleep_until_ns(start + k * 100_000_000)
        state = base.state()
        seen = seen or state.bumped or state.stalled
    assert seen


def test_a_command_nobody_repeats_stops_the_body_after_the_limit(clock: SimClock) -> None:
    # The loop's last command at 0.2 m/s, then nothing (a stalled loop): the driver's
    # watchdog sends zero 300 ms later and the emulated robot brakes at 0.6 m/s².
    sim = clock.simulation
    sim.place_robot(Pose2(8.0, 10.0, 0.0))
    config = PioneerDriverConfig()
    base, _ = lockstep_pioneer(clock, config, np.random.default_rng(0))
    start = clock.now_ns()
    drive(base, clock, 0.2, 0.0, start + 2_000_000_000)
    base.command(0.2, 0.0)  # the last command before the stall
    stall_ns, x_stall = clock.now_ns(), sim.body.pose_w[0]
    assert sim.body.velocity_base[0] == pytest.approx(0.2, abs=0.01)
    clock.sleep_until_ns(stall_ns + config.command_timeout_ns - 20_000_000)
    assert sim.body.velocity_base[0] == pytest.approx(0.2, abs=0.01)  # not before the limit
    clock.sleep_until_ns(stall_ns + 1_000_000_000)
    assert abs(sim.body.velocity_base[0]) < 0.01
    # 0.3 s at 0.2 m/s, then 0.2² / (2 x 0.6) braking: 0.093 m.
    assert sim.body.pose_w[0] - x_stall == pytest.approx(0.093, abs=0.02)
    assert base.counters().expired_commands == 1
