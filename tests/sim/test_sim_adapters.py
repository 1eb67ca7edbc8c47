"""SimFrameSource and SimBase: the shared interfaces on the lock-step simulation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from shared.camera_model import CameraModel
from shared.config import SimConfig
from shared.interfaces import FrameSource, MobileBase
from sim.sim_base import BATTERY_V, SimBase
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import Pose2, load_world


@pytest.fixture(scope="module")
def world():
    return load_world("lab")


@pytest.fixture
def sim(world) -> Simulation:
    return Simulation(world, SimConfig(seed=3))


class TestSimFrameSource:
    def test_implements_frame_source(self, sim: Simulation) -> None:
        assert isinstance(SimFrameSource(sim, CameraModel.default(), SimClock(sim)), FrameSource)

    def test_one_frame_per_period_on_the_clock(self, sim: Simulation) -> None:
        camera = CameraModel.default()
        source = SimFrameSource(sim, camera, SimClock(sim))
        times = []
        for _ in range(3):
            t_ns, image = source.read()
            assert image.shape == (camera.height, camera.width) and image.dtype == np.uint8
            assert t_ns == sim.now_ns
            times.append(t_ns)
        period, step = sim.config.frame_period_ns, sim.config.physics_dt_ns
        assert times[0] == 0
        for earlier, later in itertools.pairwise(times):
            assert period <= later - earlier < period + step
        assert source.last is not None and source.last.t_ns == times[-1]

    def test_a_loop_already_at_the_exposure_waits_no_more(self, sim: Simulation) -> None:
        clock = SimClock(sim)
        source = SimFrameSource(sim, CameraModel.default(), clock)
        source.read()
        clock.sleep_until_ns(sim.config.frame_period_ns)
        now = sim.now_ns
        t_ns, _ = source.read()
        assert t_ns == now


class TestSimBase:
    def test_implements_mobile_base(self, sim: Simulation) -> None:
        assert isinstance(SimBase(sim), MobileBase)

    def test_command_moves_odometry_and_stop_stops(self, sim: Simulation) -> None:
        sim.place_robot(Pose2(8.0, 10.0, 0.0))
        base = SimBase(sim)
        base.command(0.3, 0.0)
        sim.step_until(2_000_000_000)
        state = base.state()
        assert 0.4 < state.odom_distance_m < 0.65
        assert 0.4 < state.odom_pose[0] < 0.65 and abs(state.odom_pose[1]) < 0.05
        assert state.battery_v == BATTERY_V and state.motors_enabled
        assert not state.bumped and not state.stalled
        base.stop()
        sim.step_until(4_000_000_000)
        assert sim.body.setpoint == (0.0, 0.0)
        travelled = base.state().odom_distance_m
        sim.step_until(5_000_000_000)
        assert base.state().odom_distance_m == pytest.approx(travelled, abs=1e-3)

    def test_driving_into_a_wall_bumps_or_stalls(self, sim: Simulation) -> None:
        sim.place_robot(Pose2(8.0, 10.0, 90.0))  # the corridor's north wall ahead
        base = SimBase(sim)
        base.command(0.4, 0.0)
        seen = False
        for k in range(1, 80):
            sim.step_until(k * 100_000_000)
            state = base.state()
            seen = seen or state.bumped or state.stalled
        assert seen
