"""SimFrameSource: the frame source interface on the lock-step simulation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from shared.camera_model import CameraModel
from shared.interfaces import FrameSource
from sim.config import SimConfig
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import load_world


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
