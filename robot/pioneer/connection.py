"""Waiting for the Pioneer at start-up: the time allowed, and why it did not connect."""

from __future__ import annotations

from typing import TYPE_CHECKING

from robot.pioneer.events import ConnectFailed, TransportFailed

if TYPE_CHECKING:
    from robot.pioneer.driver import PioneerDriver

#: Wall time allowed to connect, s (ARIA's own connect gives up after about 6.4 s of SYNCs).
CONNECT_TIMEOUT_S = 10.0


def why_not_connected(driver: PioneerDriver) -> str:
    """The last transport or handshake failure the driver reported, in one line."""
    status, cause = driver.status(), ""
    while (event := driver.next_event()) is not None:
        if isinstance(event, TransportFailed):
            cause = f"; last error: {event.problem}"
        elif isinstance(event, ConnectFailed):
            cause = "; the robot did not answer the SYNC handshake"
    return (f"no Pioneer ready within {CONNECT_TIMEOUT_S:.0f} s (link {status.link.value}, "
            f"motors {'on' if status.motors_enabled else 'off'}{cause})")
