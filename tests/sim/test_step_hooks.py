"""Simulation.add_step_hook: called before every physics step with its start time and length."""

from __future__ import annotations

from sim.config import SimConfig
from sim.simulation import Simulation
from tests.sim.rooms import box_room


def test_hooks_run_in_order_before_each_step_and_may_command_the_body() -> None:
    sim = Simulation(box_room(), SimConfig())
    calls: list[tuple[str, int, int]] = []
    sim.add_step_hook(lambda now_ns, dt_ns: calls.append(("a", now_ns, dt_ns)))
    sim.add_step_hook(lambda now_ns, dt_ns: sim.body.command(0.1 if now_ns else 0.0, 0.0))
    sim.add_step_hook(lambda now_ns, dt_ns: calls.append(("b", now_ns, dt_ns)))
    sim.step()
    sim.step(5_000_000)
    dt = sim.config.physics_dt_ns
    assert calls == [("a", 0, dt), ("b", 0, dt), ("a", dt, 5_000_000), ("b", dt, 5_000_000)]
    assert sim.body.commanded == (0.1, 0.0)
