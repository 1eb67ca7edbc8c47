"""The parameter protocol (devguide parameter.md), both ends, sans-I/O.

Theory of operation
-------------------

::

    list  GCS PARAM_REQUEST_LIST -> vehicle PARAM_VALUE(i, count) for every i, paced
          GCS PARAM_REQUEST_READ(index=i) for each i it missed -> PARAM_VALUE(i)
    read  GCS PARAM_REQUEST_READ(name, index=-1) -> PARAM_VALUE(name)
    set   GCS PARAM_SET(name, value) -> PARAM_VALUE(name, value now in force)

Rules:

1. Messages in, messages out, as in ``mission.py``; ``get_timer``/``handle_timer``
   pace the list stream (vehicle) and drive retries (ground).
2. The vehicle always echoes a PARAM_SET with the value in force, also when it
   refuses the new one (out of range, not a whole number). There is no NAK in the
   protocol: a refusal or an unknown name also gets PARAM_ERROR (345, ignored by
   older stations) and a STATUSTEXT saying why (reference sec. 1.5). A refusal's
   PARAM_ERROR goes out before its echo: MAVSDK takes an echo of another value for a
   stale reply and sends the PARAM_SET again, so the vehicle would refuse (and
   report) it twice, while PARAM_ERROR ends MAVSDK's set at once.
3. Every value is REAL32 (``param_table.py``). PARAM_VALUE is a broadcast: the
   echo of one station's set tells every station.
4. The ground fetches all values with one PARAM_REQUEST_LIST, then re-reads the
   missing indexes ``_READ_WINDOW`` at a time each ``param_timeout_ns`` without
   progress; ``param_retries`` rounds in a row without a new value give up. A
   read or set is resent every ``param_timeout_ns`` until its PARAM_VALUE comes,
   ``param_retries`` times.
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass
from typing import Any

from shared.config import MavlinkConfig
from shared.errors import LocalProtocolError
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.dialect import Message, mavlink, to_float32
from shared.mavlink.param_table import ParamTable
from shared.mavlink.statustext import statustext_messages

REAL32 = mavlink.MAV_PARAM_TYPE_REAL32
#: Missing indexes re-read per round of a fetch (MAVProxy asks for up to 10 at once).
_READ_WINDOW = 10


def _name_bytes(name: str) -> bytes:
    return name.encode("ascii", errors="replace")


# ---------------------------------------------------------------------------
# Vehicle.
# ---------------------------------------------------------------------------


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
    """

    def __init__(self, table: ParamTable, address: Address,
                 config: MavlinkConfig | None = None) -> None:
        self.table = table
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
            _name_bytes(self.table.spec(index).name), self.table.value_at(index), REAL32,
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
                                                _name_bytes(msg.param_id), index, error),
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


# ---------------------------------------------------------------------------
# Ground.
# ---------------------------------------------------------------------------


class ParamOperation(enum.Enum):
    """A parameter operation of the ground station."""

    FETCH_ALL = "fetch all"
    GET = "get"
    SET = "set"


@dataclass(frozen=True, slots=True)
class ParamsFetched:
    """Every parameter of the vehicle, by name, in index order."""

    values: dict[str, float]


@dataclass(frozen=True, slots=True)
class ParamReceived:
    """The answer to a get."""

    name: str
    value: float
    index: int
    count: int


@dataclass(frozen=True, slots=True)
class ParamSetDone:
    """The vehicle's echo of a set: ``accepted`` when it took the requested value."""

    name: str
    requested: float
    value: float  #: the value in force after the set
    accepted: bool


@dataclass(frozen=True, slots=True)
class ParamOperationFailed:
    """An operation ended without an answer, or on an unknown name."""

    operation: ParamOperation
    name: str | None  #: None for a fetch of all
    reason: str


ParamClientEvent = ParamsFetched | ParamReceived | ParamSetDone | ParamOperationFailed


class ParamClient:
    """The ground station's end of the parameter protocol, talking to one vehicle.

    Args:
        address: this station.
        vehicle: the vehicle's autopilot component.
        config: timeouts and retries.
    """

    def __init__(self, address: Address, vehicle: Address,
                 config: MavlinkConfig | None = None) -> None:
        self.address = address
        self.vehicle = vehicle
        self.config = config if config is not None else MavlinkConfig()
        self._operation: ParamOperation | None = None
        self._name: str | None = None
        self._requested = 0.0
        self._count: int | None = None
        self._received: dict[int, tuple[str, float]] = {}
        self._deadline_ns: int | None = None
        self._retries = 0
        self._events: deque[ParamClientEvent] = deque()

    @property
    def operation(self) -> ParamOperation | None:
        """The operation in progress, or None when idle."""
        return self._operation

    def next_event(self) -> ParamClientEvent | None:
        """The next outcome, or None."""
        return self._events.popleft() if self._events else None

    def fetch_all(self, now_ns: int) -> list[Message]:
        """Start downloading every parameter."""
        self._start(ParamOperation.FETCH_ALL, None, now_ns)
        self._count, self._received = None, {}
        return self._request()

    def get(self, name: str, now_ns: int) -> list[Message]:
        """Start reading parameter ``name``."""
        self._start(ParamOperation.GET, name, now_ns)
        return self._request()

    def set(self, name: str, value: float, now_ns: int) -> list[Message]:
        """Start setting parameter ``name`` to ``value`` (sent as REAL32)."""
        self._start(ParamOperation.SET, name, now_ns)
        self._requested = float(value)
        return self._request()

    def _start(self, operation: ParamOperation, name: str | None, now_ns: int) -> None:
        if self._operation is not None:
            raise LocalProtocolError(f"param client: cannot start {operation.value} while "
                                     f"{self._operation.value} is in progress")
        self._operation, self._name, self._retries = operation, name, 0
        self._deadline_ns = now_ns + self.config.param_timeout_ns

    def _request(self) -> list[Message]:
        """The request(s) of the operation in progress: first try or resend."""
        ts, tc = self.vehicle.system_id, self.vehicle.component_id
        if self._operation is ParamOperation.FETCH_ALL:
            if self._count is None:
                return [mavlink.MAVLink_param_request_list_message(ts, tc)]
            missing = [i for i in range(self._count) if i not in self._received]
            return [mavlink.MAVLink_param_request_read_message(ts, tc, b"", i)
                    for i in missing[:_READ_WINDOW]]
        assert self._name is not None
        if self._operation is ParamOperation.GET:
            return [mavlink.MAVLink_param_request_read_message(ts, tc, _name_bytes(self._name), -1)]
        return [mavlink.MAVLink_param_set_message(ts, tc, _name_bytes(self._name),
                                                  self._requested, REAL32)]

    def handle_message(self, msg: Message, now_ns: int) -> list[Message]:
        """Process one received message; return the messages to send (always none)."""
        if self._operation is None or source_of(msg) != self.vehicle:
            return []
        if isinstance(msg, mavlink.MAVLink_param_value_message):
            self._on_value(msg, now_ns)
        elif (isinstance(msg, mavlink.MAVLink_param_error_message) and is_for(msg, self.address)
              and msg.param_id == self._name
              and msg.error == mavlink.MAV_PARAM_ERROR_DOES_NOT_EXIST):
            self._end(ParamOperationFailed(self._operation, self._name, "no such parameter"))
        return []

    def _on_value(self, msg: Any, now_ns: int) -> None:
        if self._operation is ParamOperation.FETCH_ALL:
            if self._count is None:
                self._count = msg.param_count
            if 0 <= msg.param_index < self._count and msg.param_index not in self._received:
                self._received[msg.param_index] = (msg.param_id, msg.param_value)
                self._retries = 0
                self._deadline_ns = now_ns + self.config.param_timeout_ns
            if len(self._received) == self._count:
                ordered = sorted(self._received.items())
                self._end(ParamsFetched({name: value for _, (name, value) in ordered}))
        elif msg.param_id == self._name:
            if self._operation is ParamOperation.GET:
                self._end(ParamReceived(msg.param_id, msg.param_value, msg.param_index,
                                        msg.param_count))
            else:
                accepted = msg.param_value == to_float32(self._requested)
                self._end(ParamSetDone(msg.param_id, self._requested, msg.param_value, accepted))

    def get_timer(self) -> int | None:
        """When the awaited answer is overdue, ns; None when idle."""
        return self._deadline_ns

    def handle_timer(self, now_ns: int) -> list[Message]:
        """Resend the request (rule 4), or give up after ``param_retries`` resends."""
        if self._deadline_ns is None or now_ns < self._deadline_ns:
            return []
        operation = self._operation
        assert operation is not None
        if self._retries >= self.config.param_retries:
            if operation is ParamOperation.FETCH_ALL:
                reason = (f"got {len(self._received)} of {self._count} parameters"
                          if self._count is not None else "no PARAM_VALUE")
            else:
                reason = f"no PARAM_VALUE after {self._retries + 1} requests"
            self._end(ParamOperationFailed(operation, self._name, reason))
            return []
        self._retries += 1
        self._deadline_ns = now_ns + self.config.param_timeout_ns
        return self._request()

    def _end(self, event: ParamClientEvent) -> None:
        self._events.append(event)
        self._operation, self._deadline_ns = None, None
