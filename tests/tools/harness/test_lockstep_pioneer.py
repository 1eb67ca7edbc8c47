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
    base.command(0.3, 0.0)
    clock.sleep_until_ns(start + 2_000_000_000)
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
    base.command(0.4, 0.0)
    start, seen = clock.now_ns(), False
    for k in range(1, 80):
        clock.sleep_until_ns(start + k * 100_000_000)
        state = base.state()
        seen = seen or state.bumped or state.stalled
    assert seen
