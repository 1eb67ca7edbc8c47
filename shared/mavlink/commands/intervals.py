"""Telemetry stream intervals per message, as MAV_CMD_SET_MESSAGE_INTERVAL (511) sets them.

The vehicle streams its telemetry by default (QGC and MAVSDK expect that of a
non-ArduPilot autopilot; reference/mavlink-vehicle.md sec. 3); MAVSDK then tunes
single messages with SET_MESSAGE_INTERVAL: param1 = message id, param2 = interval
in us, -1 to stop, 0 for the default. Only messages with a default can be
streamed; intervals are floored at ``min_interval_ns`` to cap the link load.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from shared.mavlink.dialect import mavlink


class MessageIntervals:
    """The interval of every streamable message: a default, overridable per message.

    Args:
        defaults_ns: message id -> default interval, ns (e.g. ``{0: 1_000_000_000}``).
        min_interval_ns: shortest interval a request may set, ns.
    """

    def __init__(self, defaults_ns: Mapping[int, int], min_interval_ns: int = 50_000_000) -> None:
        if any(v <= 0 for v in defaults_ns.values()) or min_interval_ns <= 0:
            raise ValueError("intervals must be > 0 ns")
        self._defaults = dict(defaults_ns)
        self._min_ns = min_interval_ns
        self._current: dict[int, int | None] = dict(self._defaults)

    def interval_ns(self, msg_id: int) -> int | None:
        """The interval to stream ``msg_id`` at, ns; None when it is off or not streamable."""
        return self._current.get(msg_id)

    def set_interval(self, msg_id: float, interval_us: float) -> int:
        """Apply SET_MESSAGE_INTERVAL's param1 and param2.

        Returns:
            ``MAV_RESULT_ACCEPTED``, or ``MAV_RESULT_DENIED`` for a message we do not
            stream or an interval that is not -1, 0 or > 0.
        """
        if not (math.isfinite(msg_id) and msg_id in self._defaults and math.isfinite(interval_us)):
            return mavlink.MAV_RESULT_DENIED
        key = int(msg_id)
        if interval_us == -1:
            self._current[key] = None
        elif interval_us == 0:
            self._current[key] = self._defaults[key]
        elif interval_us > 0:
            self._current[key] = max(round(interval_us * 1000), self._min_ns)
        else:
            return mavlink.MAV_RESULT_DENIED
        return mavlink.MAV_RESULT_ACCEPTED
