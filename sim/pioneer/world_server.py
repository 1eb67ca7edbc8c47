"""A world served as an emulated Pioneer: the simulation, the ARIA server, the camera feed.

What ``vmnav sim serve`` and the hardware-in-the-loop rig run: the world of a
:class:`~shared.config.SimConfig` built into a :class:`~sim.simulation.Simulation`, its
robot an :class:`~sim.pioneer.emulator.EmulatedPioneer` behind a
:class:`~sim.pioneer.server.PioneerServer`, optionally filmed for a
:class:`~sim.camera_server.CameraServer`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from sim.camera_server import CameraFeed
from sim.pioneer.emulator import EmulatedPioneer
from sim.pioneer.server import PioneerServer
from sim.simulation import Simulation
from sim.world import load_world

if TYPE_CHECKING:
    from shared.byte_link import ByteLink
    from shared.camera_model import CameraModel
    from sim.camera_server import CameraServer
    from sim.config import SimConfig
    from sim.pioneer.links import TcpListener

EMULATOR_SEED_CHILD = 3
"""The emulator's sonar noise draws from child 3 of the seed (the simulation uses 0-2)."""


def pioneer_server(config: SimConfig, camera: CameraModel, links: Sequence[ByteLink],
                   listeners: Sequence[TcpListener],
                   video: CameraServer | None) -> PioneerServer:
    """The world of ``config`` with its robot as an emulated Pioneer served on ``links``
    and ``listeners``, and filmed through ``camera`` for ``video`` when given.

    The emulator's sonar noise draws from child :data:`EMULATOR_SEED_CHILD` of
    ``config.seed``. The simulation is ``server.emulator.simulation``; its step hooks so
    far are the emulator's, then the camera feed's (others go after). The server owns
    ``links`` and ``listeners`` (closing it closes them) and has not started running.

    Raises:
        ConfigError: the world cannot be loaded.
    """
    sim = Simulation(load_world(config.world), config)
    seed = np.random.SeedSequence(config.seed).spawn(EMULATOR_SEED_CHILD + 1)[-1]
    server = PioneerServer(EmulatedPioneer(sim, config.emulator, np.random.default_rng(seed)),
                           links, listeners)
    if video is not None:
        sim.add_step_hook(CameraFeed(sim, camera, video))
    return server
