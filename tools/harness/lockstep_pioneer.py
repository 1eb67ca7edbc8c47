"""The simulated robot's base in lock-step: our ARIA driver on the emulated Pioneer.

Issue 5, item 4: the route follower in ``vmnav demo`` drives the simulator's body
through the same code that drives a real Pioneer 3-AT. The robot's
:class:`robot.pioneer.driver.PioneerDriver` (a :class:`shared.interfaces.MobileBase`)
and the simulator's :class:`sim.pioneer.emulator.EmulatedPioneer` speak ARIA over an
in-memory byte pipe (:func:`shared.byte_link.pipe_pair`); one step hook services
both ends before every physics step, so the exchange is deterministic and as fast
as the machine allows. Velocity commands travel as VEL/RVEL (mm/s, whole deg/s),
odometry comes back in the SIPs every 100 ms of simulated time, as on the robot.

It couples ``robot/`` and ``sim/``, so it lives in the harness (tools/harness/).
"""

from __future__ import annotations

import numpy as np

from robot.config import PioneerDriverConfig
from robot.pioneer.driver import PioneerDriver
from shared.byte_link import ByteLink, pipe_pair
from shared.errors import TransportError
from sim.pioneer.emulator import EmulatedPioneer
from sim.pioneer.server import PioneerServer
from sim.sim_clock import SimClock

#: Simulated time allowed for the handshake, ns (it takes about 0.2 s).
CONNECT_TIMEOUT_NS = 5_000_000_000


def lockstep_pioneer(clock: SimClock, config: PioneerDriverConfig,
                     rng: np.random.Generator) -> tuple[PioneerDriver, PioneerServer]:
    """Connect a driver to an emulated Pioneer on ``clock``'s simulation, motors enabled.

    Args:
        clock: the lock-step clock of the simulation whose body the emulator drives.
        config: the driver's policy (speed limits, timers).
        rng: the emulator's sonar noise.

    Returns:
        The connected driver (the robot's base) and the emulator's server (its
        ``emulator`` has the counters; its faults, ``cut`` and ``inject``, act in lock-step).

    Raises:
        TransportError: the handshake did not complete within :data:`CONNECT_TIMEOUT_NS`.
    """
    sim = clock.simulation
    emulator = EmulatedPioneer(sim, sim.config.emulator, rng)
    server = PioneerServer(emulator, links=[])

    def plug_in() -> ByteLink:
        """A new cable for every (re)connection, as a serial adapter re-opened."""
        robot_end, host_end = pipe_pair()
        server.links.append(robot_end)
        return host_end

    driver = PioneerDriver(plug_in, clock, config)

    def exchange(now_ns: int, dt_ns: int) -> None:
        driver.service(now_ns)
        server.pump()

    sim.add_step_hook(exchange)
    if not driver.wait_connected(CONNECT_TIMEOUT_NS):
        raise TransportError("pipe", f"the emulated Pioneer did not connect within "
                                     f"{CONNECT_TIMEOUT_NS / 1e9:.0f} s ({driver.status()})")
    return driver, server
