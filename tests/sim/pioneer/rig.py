"""A lock-step test rig: simulation, emulated Pioneer, server tick and an ARIA host on a pipe."""

from __future__ import annotations

import numpy as np

from shared.aria import Command, ConnState, Sip
from shared.byte_link import pipe_pair
from shared.pose import Pose2
from sim.config import EmulatorConfig, SimConfig
from sim.pioneer.emulator import EmulatedPioneer
from sim.pioneer.server import PioneerServer
from sim.simulation import Simulation
from sim.world import World
from tests.sim.pioneer.aria_host import AriaHost
from tests.sim.rooms import box_room

OPEN_STATES = (ConnState.OPEN, ConnState.RUNNING)


class Rig:
    """Everything in one process, stepped by :meth:`run_for` (simulation time only).

    Args:
        world: the place; None = a bare 12 m x 6 m room, the robot at its centre facing +x.
        config: the emulator's configuration.
        start: where to place the robot; None = the world's start.
        seed: simulation and sonar-noise seed.
    """

    def __init__(
        self,
        world: World | None = None,
        config: EmulatorConfig | None = None,
        start: Pose2 | None = None,
        seed: int = 1,
    ) -> None:
        self.sim = Simulation(world or box_room((12.0, 6.0)), SimConfig(seed=seed))
        if start is not None:
            self.sim.place_robot(start)
        self.emulator = EmulatedPioneer(
            self.sim, config or EmulatorConfig(), np.random.default_rng(seed)
        )
        self.robot_end, self.host_end = pipe_pair()
        self.server = PioneerServer(self.emulator, links=[self.robot_end])
        self.host = AriaHost(self.host_end)

    @property
    def now_ns(self) -> int:
        return self.sim.now_ns

    def run_for(self, seconds: float) -> None:
        """Tick the server and poll the host for ``seconds`` of simulation time."""
        end = self.now_ns + round(seconds * 1e9)
        while self.now_ns < end:
            self.server.tick()
            self.host.poll(self.now_ns)

    def connect(self, timeout_s: float = 1.0) -> None:
        """Handshake and OPEN with the current host, until its first SIP; fails the test
        if that does not happen within ``timeout_s`` of simulation time."""
        self.host.connect(self.now_ns)
        end = self.now_ns + round(timeout_s * 1e9)
        while not self.host.sips and self.now_ns < end:
            self.run_for(0.01)
        assert self.host.session.state in OPEN_STATES and self.host.sips, self.host.events

    def run_until_sip(self) -> Sip:
        """Run until a SIP arrives; returns it (sent at the current time)."""
        count = len(self.host.sips)
        while len(self.host.sips) == count:
            self.run_for(0.01)
        return self.host.sips[-1][1]

    def command(self, command: Command, arg: int | None = None) -> None:
        self.host.command(command, arg, self.now_ns)

    def new_host(self, **kwargs: bool) -> AriaHost:
        """A new client on the same pipe (the old one vanished without a word)."""
        self.host = AriaHost(self.host_end, **kwargs)
        return self.host
