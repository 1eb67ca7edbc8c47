from __future__ import annotations

import pytest

from shared.clock import Clock
from shared.pose import Pose2
from sim.config import SimConfig
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from tests.sim.rooms import box_room


@pytest.fixture
def sim() -> Simulation:
    world = box_room((6.0, 4.0), Pose2(1.0, 2.0))
    return Simulation(world, SimConfig(physics_dt_ns=10_000_000, landmark_density_scale=0.0))


class TestSimClock:
    def test_sleeping_one_second_takes_exactly_100_steps(self, sim: Simulation) -> None:
        clock: Clock = SimClock(sim)
        steps = []
        sim.body.command(0.2, 0.0)
        original = sim.step

        def counting_step(dt_ns: int | None = None) -> None:
            steps.append(dt_ns)
            original(dt_ns)

        sim.step = counting_step  # type: ignore[method-assign]
        clock.sleep_until_ns(1_000_000_000)
        assert len(steps) == 100
        assert clock.now_ns() == 1_000_000_000

    def test_a_deadline_in_the_past_does_nothing(self, sim: Simulation) -> None:
        clock = SimClock(sim)
        clock.sleep_until_ns(50_000_000)
        clock.sleep_until_ns(20_000_000)
        assert clock.now_ns() == 50_000_000

    def test_a_deadline_between_steps_ends_on_the_next_step(self, sim: Simulation) -> None:
        clock = SimClock(sim)
        clock.sleep_until_ns(25_000_001)
        assert clock.now_ns() == 30_000_000

    def test_a_frame_loop_runs_in_lock_step_without_drift(self, sim: Simulation) -> None:
        clock = SimClock(sim)
        period_ns = 66_666_667  # 15 frames/s
        deadline = clock.now_ns()
        frame_times = []
        for _ in range(150):
            deadline += period_ns
            clock.sleep_until_ns(deadline)
            frame_times.append(clock.now_ns())
        # Every frame lands on the first physics step at or after its deadline: no drift.
        step_ns = 10_000_000
        assert frame_times == [-(-k * period_ns // step_ns) * step_ns for k in range(1, 151)]
