"""The lock-step clock: simulation time, advanced by stepping the simulation.

``sleep_until_ns`` does not wait: it steps the physics by fixed steps of
``config.physics_dt_ns`` until the simulation's time reaches the deadline, so a
loop written against :class:`shared.clock.Clock` runs the world in lock-step,
as fast as the machine allows and deterministically. Time stays on the physics
step grid: a deadline between two steps is reached at the next step.
"""

from __future__ import annotations

from sim.simulation import Simulation


class SimClock:
    """A :class:`shared.clock.Clock` over a simulation's time.

    Args:
        simulation: the simulation to read and step.
    """

    def __init__(self, simulation: Simulation) -> None:
        self.simulation = simulation

    def now_ns(self) -> int:
        """Simulation time since the start, ns."""
        return self.simulation.now_ns

    def sleep_until_ns(self, deadline_ns: int) -> None:
        """Step the simulation until ``now_ns() >= deadline_ns`` (no-op if already past)."""
        self.simulation.step_until(deadline_ns)
