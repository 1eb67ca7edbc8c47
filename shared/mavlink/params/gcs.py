"""The parameter protocol, ground side (devguide parameter.md), sans-I/O.

Theory of operation
-------------------

The exchanges are drawn in :mod:`shared.mavlink.params`. One operation at a time:
:meth:`ParamClient.fetch_all`, :meth:`~ParamClient.get` or :meth:`~ParamClient.set`
returns the first messages to send and starts a deadline; ``handle_message`` and
``handle_timer`` return what to send next; the outcome is one event (``next_event``).

Rules:

1. Only messages from the vehicle (``vehicle`` address) count; a PARAM_ERROR also
   has to be addressed to this station (or broadcast).
2. The ground fetches all values with one PARAM_REQUEST_LIST, then re-reads the
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
from shared.mavlink.params.table import REAL32, param_id_from_name

#: Missing indexes re-read per round of a fetch (MAVProxy asks for up to 10 at once).
_READ_WINDOW = 10


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
            return [mavlink.MAVLink_param_request_read_message(
                ts, tc, param_id_from_name(self._name), -1)]
        return [mavlink.MAVLink_param_set_message(ts, tc, param_id_from_name(self._name),
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
        """Resend the request (rule 2), or give up after ``param_retries`` resends."""
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
