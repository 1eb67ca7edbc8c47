"""The command protocol, ground side (devguide command.md), sans-I/O.

Theory of operation
-------------------

:meth:`CommandClient.send` returns the COMMAND_LONG to send and starts a deadline;
``handle_message`` takes the vehicle's COMMAND_ACKs; the outcome is one event.

Rules:

1. One command at a time, to one vehicle (``vehicle`` address). Only a COMMAND_ACK
   from it, for the command in flight, addressed to this station (or broadcast)
   counts.
2. ``MAV_RESULT_IN_PROGRESS`` is not an outcome: the vehicle has the command, so
   there are no more resends; without another ACK for ``timeout_ns`` after the last
   one it times out. Every other result ends the command.
3. Without an ACK for ``timeout_ns`` the command is resent with ``confirmation``
   one higher (the vehicle answers a repeat from its cache, so nothing runs twice),
   up to ``retries`` resends; then :class:`CommandTimedOut`.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

from shared.errors import LocalProtocolError
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.dialect import Message, mavlink


def result_name(result: int) -> str:
    """E.g. ``"MAV_RESULT_DENIED"`` for a ``MAV_RESULT``."""
    entry = mavlink.enums["MAV_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_RESULT {result}"


@dataclass(frozen=True, slots=True)
class CommandDone:
    """The vehicle answered the command."""

    command: int  #: the MAV_CMD
    result: int  #: the MAV_RESULT
    result_param2: int = 0  #: the ACK's ``result_param2`` (the command's own meaning)

    @property
    def accepted(self) -> bool:
        """``MAV_RESULT_ACCEPTED``."""
        return self.result == mavlink.MAV_RESULT_ACCEPTED


@dataclass(frozen=True, slots=True)
class CommandTimedOut:
    """No COMMAND_ACK after every resend."""

    command: int
    sends: int  #: COMMAND_LONGs sent


CommandEvent = CommandDone | CommandTimedOut


class CommandClient:
    """The ground station's end of the command protocol (module rules).

    Args:
        address: this station.
        vehicle: the vehicle's component the commands go to.
        timeout_ns: wait this long for an ACK before resending, ns.
        retries: resends before giving up.
    """

    def __init__(self, address: Address, vehicle: Address, timeout_ns: int = 1_000_000_000,
                 retries: int = 3) -> None:
        self.address = address
        self.vehicle = vehicle
        self.timeout_ns = timeout_ns
        self.retries = retries
        self._params: tuple[float, ...] = ()
        self._command: int | None = None
        self._confirmation = 0
        self._in_progress = False
        self._deadline_ns: int | None = None
        self._events: deque[CommandEvent] = deque()

    @property
    def busy(self) -> bool:
        """A command waits for its outcome."""
        return self._command is not None

    def next_event(self) -> CommandEvent | None:
        """The next outcome, or None."""
        return self._events.popleft() if self._events else None

    def send(self, command: int, params: tuple[float, ...], now_ns: int) -> list[Message]:
        """Start ``command`` with up to seven params (the rest NaN, "unset" as MAVSDK sends).

        Raises:
            LocalProtocolError: another command is in flight, or more than seven params.
        """
        if self._command is not None:
            raise LocalProtocolError(f"command client: command {command} while "
                                     f"{self._command} waits for its ACK")
        if len(params) > 7:
            raise LocalProtocolError(f"command {command}: {len(params)} params (at most 7)")
        self._command, self._confirmation, self._in_progress = command, 0, False
        self._params = tuple(params) + (math.nan,) * (7 - len(params))
        return self._transmit(now_ns)

    def _transmit(self, now_ns: int) -> list[Message]:
        assert self._command is not None
        self._deadline_ns = now_ns + self.timeout_ns
        return [mavlink.MAVLink_command_long_message(
            self.vehicle.system_id, self.vehicle.component_id, self._command,
            self._confirmation, *self._params)]

    def handle_message(self, msg: Message, now_ns: int) -> list[Message]:
        """Process one received message; return the messages to send (always none)."""
        ack: Any = msg
        if (self._command is None or not isinstance(msg, mavlink.MAVLink_command_ack_message)
                or source_of(msg) != self.vehicle or not is_for(msg, self.address)
                or ack.command != self._command):
            return []
        if ack.result == mavlink.MAV_RESULT_IN_PROGRESS:
            self._deadline_ns = now_ns + self.timeout_ns
            self._in_progress = True
            return []
        self._events.append(CommandDone(self._command, ack.result,
                                        getattr(ack, "result_param2", 0)))
        self._command, self._deadline_ns = None, None
        return []

    def get_timer(self) -> int | None:
        """When the ACK is overdue, ns; None when idle."""
        return self._deadline_ns

    def handle_timer(self, now_ns: int) -> list[Message]:
        """Resend the command, or give up after ``retries`` resends (rule 3)."""
        if self._command is None or self._deadline_ns is None or now_ns < self._deadline_ns:
            return []
        if self._in_progress or self._confirmation >= self.retries:
            self._events.append(CommandTimedOut(self._command, self._confirmation + 1))
            self._command, self._deadline_ns = None, None
            return []
        self._confirmation += 1
        return self._transmit(now_ns)
