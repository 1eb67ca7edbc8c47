"""The robot-side ARIA driver for a Pioneer 3-AT (issue 5).

* ``client``: :class:`PioneerClient`, the sans-I/O host end (connect sequence,
  keep-alive, commands, odometry, link-loss detection, events);
* ``driver``: :class:`PioneerDriver`, a :class:`~shared.interfaces.MobileBase` over a
  byte link and a clock, with its own I/O thread and automatic reconnection;
* ``serial_link``: :func:`serial_link_factory`, the Pioneer's link from its address
  (``tcp:``, ``serial:``, ``pty:``, a device path, ``socket://``; the adapters are
  ``shared.serial_port.SerialLink`` and ``shared.stream_link``), and
  :func:`aria_address`;
* ``odometry``, ``events``, ``status``: the pieces they report with;
* ``shutdown``: :func:`close_on_sigterm`; ``connection``: the time allowed to connect at
  start-up and why a driver did not connect.
"""

from robot.pioneer.client import PioneerClient
from robot.pioneer.driver import PioneerDriver
from robot.pioneer.serial_link import SerialLink, serial_link_factory
from robot.pioneer.shutdown import close_on_sigterm
from robot.pioneer.status import LinkCounters, LinkState, PioneerStatus

__all__ = [
    "LinkCounters",
    "LinkState",
    "PioneerClient",
    "PioneerDriver",
    "PioneerStatus",
    "SerialLink",
    "close_on_sigterm",
    "serial_link_factory",
]
