"""Time as integer nanoseconds, from an injected clock.

Loops hold a :class:`Clock` and schedule by deadline::

    deadline_ns += period_ns
    clock.sleep_until_ns(deadline_ns)

Nothing below a loop calls ``time.*``. The simulator's lock-step clock
(``sim.sim_clock.SimClock``) implements the same protocol and steps the physics
while it "sleeps".
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Protocol

logger = logging.getLogger(__name__)

NS_PER_S = 1_000_000_000


class Clock(Protocol):
    """A monotonic source of integer nanoseconds that can wait for a deadline."""

    def now_ns(self) -> int:
        """Current time, ns, monotonic (epoch is the clock's own)."""
        ...

    def sleep_until_ns(self, deadline_ns: int) -> None:
        """Return once ``now_ns() >= deadline_ns``; return at once if already past."""
        ...


class WallClock:
    """The real monotonic clock (``time.monotonic_ns``)."""

    def now_ns(self) -> int:
        return time.monotonic_ns()

    def sleep_until_ns(self, deadline_ns: int) -> None:
        remaining_ns = deadline_ns - time.monotonic_ns()
        if remaining_ns > 0:
            time.sleep(remaining_ns / NS_PER_S)


class ManualClock:
    """A clock that moves only when told to; for tests.

    ``sleep_until_ns`` jumps straight to the deadline, so timer logic runs
    instantly and deterministically. Time never goes backwards.

    Args:
        start_ns: the initial reading, ns.
    """

    def __init__(self, start_ns: int = 0) -> None:
        self._now_ns = int(start_ns)

    def now_ns(self) -> int:
        return self._now_ns

    def sleep_until_ns(self, deadline_ns: int) -> None:
        self._now_ns = max(self._now_ns, int(deadline_ns))

    def advance_ns(self, delta_ns: int) -> None:
        """Move time forward by ``delta_ns`` (>= 0) nanoseconds.

        Raises:
            ValueError: if ``delta_ns`` is negative.
        """
        if delta_ns < 0:
            raise ValueError(f"ManualClock cannot go backwards (asked to advance {delta_ns} ns)")
        self._now_ns += int(delta_ns)

    def advance(self, seconds: float) -> None:
        """Move time forward by ``seconds`` (>= 0), rounded to the nearest ns."""
        self.advance_ns(round(seconds * NS_PER_S))


def unix_offset_ns(clock: Clock) -> int:
    """Unix time minus ``clock``'s reading now, ns: what turns the clock's times into Unix
    times (logs, signing). Entry points measure it once, when they open what needs it; a
    wall clock's offset then drifts only as NTP slews the system time.

    A lock-step :class:`~sim.sim_clock.SimClock` measured at its start puts the simulated
    clock's zero at the wall time the run started.
    """
    return time.time_ns() - clock.now_ns()


def ns_from_s(seconds: float) -> int:
    """Seconds to integer nanoseconds, rounded to the nearest ns."""
    return round(seconds * NS_PER_S)


def s_from_ns(nanoseconds: int) -> float:
    """Integer nanoseconds to float seconds (for math only)."""
    return nanoseconds / NS_PER_S


def service_loop(service: Callable[[int], None], clock: Clock, period_ns: int,
                 stop: threading.Event, name: str) -> None:
    """Call ``service(now_ns)`` every ``period_ns`` on ``clock`` until ``stop`` is set.

    The body of an I/O thread (the ARIA driver's, the MAVLink vehicle's). Deadlines
    advance by the period; a late round does not make the next ones hurry. An
    exception is a bug: it is logged with ``name`` and ends the thread.
    """
    deadline_ns = clock.now_ns()
    try:
        while not stop.is_set():
            service(clock.now_ns())
            deadline_ns = max(deadline_ns + period_ns, clock.now_ns())
            clock.sleep_until_ns(deadline_ns)
    except Exception:
        logger.exception("%s: I/O thread died", name)
        raise
