"""The parameter protocol, vehicle side (devguide parameter.md), sans-I/O.

Theory of operation
-------------------

The exchanges are drawn in :mod:`shared.mavlink.params`. Rules:

1. Messages in, messages out, as in ``mission/vehicle.py``; ``get_timer`` and
   ``handle_timer`` pace the list stream.
2. The vehicle always echoes a PARAM_SET with the value in force, also when it
   refuses the new one (out of range, not a whole number). There is no NAK in the
   protocol: a refusal or an unknown name also gets PARAM_ERROR (345, ignored by
   older stations) and a STATUSTEXT saying why (reference sec. 1.5). A refusal's
   PARAM_ERROR goes out before its echo: MAVSDK takes an echo of another value for a
   stale reply and sends the PARAM_SET again, so the vehicle would refuse (and
   report) it twice, while PARAM_ERROR ends MAVSDK's set at once.
3. Every value is REAL32 (``table.py``). PARAM_VALUE is a broadcast: the echo of
   one station's set tells every station.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shared.config import MavlinkConfig
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.params.table import REAL32, ParamTable, param_id_from_name
from shared.mavlink.statustext import statustext_messages


@dataclass(frozen=True, slots=True)
class ParamChanged:
    """A PARAM_SET changed a value; the application applies (and persists) it."""

    name: str
    value: float
    previous: float
    source: Address


@dataclass(frozen=True, slots=True)
class ParamRefused:
    """A PARAM_SET was refused; the value in force was echoed."""

    name: str
    value: float
    reason: str
    source: Address


class ParamServer:
    """The vehicle's end of the parameter protocol over a :class:`ParamTable`.

    Args:
        table: the parameters; the server sets values in it.
        address: this vehicle, for filtering requests.
        config: the list pacing.
        check: the vehicle's own test of a value that is in range: the problem it makes
            with the other parameters (e.g. a slow-down distance below the stop
            distance), None when it fits; refused like an out-of-range value.
    """

    def __init__(self, table: ParamTable, address: Address,
                 config: MavlinkConfig | None = None,
                 check: Callable[[str, float], str | None] | None = None) -> None:
        self.table = table
        self._check = check
        self.address = address
        self.config = config if config is not None else MavlinkConfig()
        self._stream: deque[int] = deque()
        self._next_stream_ns = 0
        self._events: deque[ParamChanged | ParamRefused] = deque()
        self._notice_id = 0

    def next_event(self) -> ParamChanged | ParamRefused | None:
        """The next event for the application, or None."""
        return self._events.popleft() if self._events else None

    def value_message(self, index: int) -> mavlink.MAVLink_param_value_message:
        """PARAM_VALUE for the parameter at ``index`` (also to broadcast a change)."""
        return mavlink.MAVLink_param_value_message(
            param_id_from_name(self.table.spec(index).name), self.table.value_at(index), REAL32,
            len(self.table), index)

    def handle_message(self, msg: Message, now_ns: int) -> list[Message]:
        """Process one received message; return the messages to send."""
        if not is_for(msg, self.address):
            return []
        if isinstance(msg, mavlink.MAVLink_param_request_list_message):
            self._stream = deque(range(len(self.table)))
            self._next_stream_ns = now_ns
            return self.handle_timer(now_ns)
        if isinstance(msg, mavlink.MAVLink_param_request_read_message):
            index = msg.param_index if msg.param_index >= 0 else self.table.index(msg.param_id)
            if index is None or index >= len(self.table):
                return self._error(msg, mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST,
                                   f"param {msg.param_id or msg.param_index}: no such parameter")
            return [self.value_message(index)]
        if isinstance(msg, mavlink.MAVLink_param_set_message):
            return self._on_set(msg)
        return []

    def _on_set(self, msg: Any) -> list[Message]:
        name, value, source = msg.param_id, float(msg.param_value), source_of(msg)
        index = self.table.index(name)
        if index is None:
            return self._error(msg, mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST,
                               f"param {name}: no such parameter")
        problem = self.table.problem(name, value)
        if problem is None and self._check is not None:
            problem = self._check(name, value)
        if problem is not None:
            self._events.append(ParamRefused(name, value, problem, source))
            return [*self._error(msg, mavlink.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE,
                                 f"param {name}: {problem}"), self.value_message(index)]
        previous = self.table.value_at(index)
        self.table.set(name, value)
        if value != previous:
            self._events.append(ParamChanged(name, value, previous, source))
        return [self.value_message(index)]

    def _error(self, msg: Any, error: int, text: str) -> list[Message]:
        source = source_of(msg)
        index = getattr(msg, "param_index", -1)
        self._notice_id = self._notice_id % 0xFFFF + 1
        return [
            mavlink.MAVLink_param_error_message(source.system_id, source.component_id,
                                                param_id_from_name(msg.param_id), index, error),
            *statustext_messages(mavlink.MAV_SEVERITY_WARNING, text, self._notice_id),
        ]

    def get_timer(self) -> int | None:
        """When the next streamed PARAM_VALUE is due, ns; None when not streaming."""
        return self._next_stream_ns if self._stream else None

    def handle_timer(self, now_ns: int) -> list[Message]:
        """Send the next streamed PARAM_VALUE if due (one per ``param_stream_period_ns``)."""
        if not self._stream or now_ns < self._next_stream_ns:
            return []
        period = self.config.param_stream_period_ns
        self._next_stream_ns += period
        if self._next_stream_ns <= now_ns:  # called late: re-anchor, no burst
            self._next_stream_ns = now_ns + period
        return [self.value_message(self._stream.popleft())]
