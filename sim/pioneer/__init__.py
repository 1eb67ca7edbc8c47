"""The emulated Pioneer 3-AT: an ARIA server on the simulated body (issue 5).

The robot as ARIA knows it (subclass, conversion factors, sonar geometry) is
:mod:`shared.aria.p3at`: the robot's driver reads the same geometry.

Modules:

* ``motion``: the firmware's motion controller (targets, limits, velocity profile).
* ``sonar``: the two sonar arrays (firing schedule, a cone of pymunk rays per ping).
* ``emulator``: :class:`EmulatedPioneer`, the sans-I/O ARIA server.
* ``links``: pty and TCP byte links; ``server``: :class:`PioneerServer`, one client at
  a time, tick by tick or in real time (``vmnav sim serve``); ``world_server``: a world
  served as an emulated Pioneer with its camera feed.
"""

from sim.pioneer.emulator import EmulatedPioneer, EmulatorStats
from sim.pioneer.links import PtyLink, StreamLink, TcpListener
from sim.pioneer.server import PioneerServer

__all__ = [
    "EmulatedPioneer",
    "EmulatorStats",
    "PioneerServer",
    "PtyLink",
    "StreamLink",
    "TcpListener",
]
