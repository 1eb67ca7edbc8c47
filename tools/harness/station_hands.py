"""The HIL demo's scripted operator's hands on the ground station: on the demo's own thread,
or through the web app's station loop while ``vmnav demo --hil --web`` serves the page.

The station is not thread-safe (``ground.station``): with the web app, the loop's thread
owns it (``ground.web.station_loop`` rule 1), so every step of the operator is work
submitted to that loop, in turn with the page's requests, and waiting is this thread's
sleep while the loop services the link.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from ground.station import GroundStation
from ground.web.station_loop import StationLoop
from shared.clock import Clock

T = TypeVar("T")
#: While the loop owns the station, a wait checks its condition this often, ns.
POLL_NS = 20_000_000


def _never(station: GroundStation) -> bool:
    return False


class StationHands:
    """Runs the operator's steps on ``station``: directly, or on ``loop``'s thread.

    Args:
        station: the ground station.
        clock: the station's clock.
        loop: the web app's station loop, started; None: this thread uses the station.
    """

    def __init__(self, station: GroundStation, clock: Clock,
                 loop: StationLoop | None = None) -> None:
        self.station = station
        self._clock = clock
        self._loop = loop

    def do(self, action: Callable[[GroundStation], T]) -> T:
        """``action(station)``'s result (its exception raised here)."""
        if self._loop is None:
            return action(self.station)
        return self._loop.submit(action).result()

    def wait(self, duration_ns: int,
             until: Callable[[GroundStation], bool] = _never) -> None:
        """Service the link for ``duration_ns``, or until ``until(station)`` holds."""
        if self._loop is None:
            self.station.run_until(lambda: until(self.station), duration_ns)
            return
        deadline_ns = self._clock.now_ns() + duration_ns
        while not self.do(until) and (now_ns := self._clock.now_ns()) < deadline_ns:
            self._clock.sleep_until_ns(min(deadline_ns, now_ns + POLL_NS))
