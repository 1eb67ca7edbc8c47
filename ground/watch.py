"""Live telemetry lines (``vmnav ground watch``): one per message shown and per notice.

Each line starts with the time since the watch began (s, ``%8.2f``) and the vehicle's
system id; a message's new notices (STATUSTEXT, joined by ``ground.fleet``) come
before its own line, once each, and a message ``telemetry_text.describe`` does not
show adds no line, e.g.::

        1.02 s  vehicle 1  NOTICE: mission localizing: localizing the start
        1.02 s  vehicle 1  HEARTBEAT: mode AUTO, active
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ground.fleet import VehicleState
from ground.station import GroundStation
from ground.telemetry_text import describe
from shared.clock import NS_PER_S


class WatchLines:
    """The lines of each message from a vehicle (module docstring; pure)."""

    def __init__(self) -> None:
        self._shown: dict[int, int] = {}  # system id -> notices already shown

    def lines(self, vehicle: VehicleState, msg: Any, elapsed_s: float) -> list[str]:
        """The lines for ``msg`` from ``vehicle``, ``elapsed_s`` s after the watch began:
        the vehicle's notices not shown yet, then the message's line if it has one."""
        stamp = f"{elapsed_s:8.2f} s  vehicle {vehicle.system_id}"
        notices = vehicle.notices[self._shown.get(vehicle.system_id, 0):]
        self._shown[vehicle.system_id] = len(vehicle.notices)
        out = [f"{stamp}  NOTICE: {notice}" for notice in notices]
        line = describe(msg)
        if line is not None:
            out.append(f"{stamp}  {msg.get_type()}: {line}")
        return out


def watch(station: GroundStation, write: Callable[[str], None], duration_ns: int) -> None:
    """Run ``station`` for ``duration_ns`` (clock ns), writing the lines of every message
    from every vehicle it hears; an exception (Ctrl-C) ends it early."""
    start_ns = station.clock.now_ns()
    watch_lines = WatchLines()

    def show(vehicle: VehicleState, msg: Any) -> None:
        elapsed_s = (station.clock.now_ns() - start_ns) / NS_PER_S
        for line in watch_lines.lines(vehicle, msg, elapsed_s):
            write(line)

    station.listeners.append(show)
    try:
        station.run_until(lambda: False, duration_ns)
    finally:
        station.listeners.remove(show)
