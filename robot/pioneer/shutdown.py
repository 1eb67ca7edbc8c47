"""Close the driver cleanly when the process is told to stop (SIGTERM).

A service manager stops the robot program with SIGTERM. Python's default is to die
at once, and the robot keeps its last velocity until its 2 s watchdog trips
(reference §7). The handler installed here closes the driver (VEL 0, RVEL 0,
ENABLE 0, CLOSE) and then raises ``SystemExit(128 + SIGTERM)``, so ``finally``
blocks and context managers still run.
"""

from __future__ import annotations

import signal
from collections.abc import Callable
from types import FrameType
from typing import Protocol


class Closeable(Protocol):
    def close(self) -> None: ...


def close_on_sigterm(driver: Closeable) -> Callable[[], None]:
    """Install a SIGTERM handler that closes ``driver``, then exits with status 143.

    Call from the main thread (``signal.signal``'s rule).

    Returns:
        A function that restores the previous handler.
    """
    previous = signal.getsignal(signal.SIGTERM)

    def on_sigterm(signum: int, frame: FrameType | None) -> None:
        driver.close()
        raise SystemExit(128 + signum)

    signal.signal(signal.SIGTERM, on_sigterm)
    return lambda: signal.signal(signal.SIGTERM, previous)
