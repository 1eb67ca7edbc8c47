"""The mission protocol, ground side (devguide mission.md), sans-I/O.

Theory of operation
-------------------

One operation at a time: :meth:`MissionClient.upload`, :meth:`~MissionClient.download`
or :meth:`~MissionClient.clear` returns the first message to send and starts a
deadline; ``handle_message`` and ``handle_timer`` return what to send next; the
outcome is one event (``next_event``).

Rules:

1. Only messages from the vehicle (``vehicle`` address) and addressed to this
   station (or broadcast) count; the rest are ignored.
2. Timeouts (devguide): ``mission_timeout_ns`` for MISSION_COUNT, MISSION_ACK and
   the vehicle's next request during an upload; ``mission_item_timeout_ns`` for an
   item we asked for. On a timeout the last message is resent, up to
   ``mission_retries`` times in a row without an answer; then the station cancels
   (MISSION_ACK OPERATION_CANCELLED) and reports :class:`OperationTimedOut`.
3. Upload: the vehicle drives the transfer; any requested item is sent, in any
   order. MISSION_ACK ACCEPTED counts only once every item was requested: an ACK
   left over from an earlier operation cannot end an upload early.
4. Download: items are requested one by one, in order; an item out of order is
   dropped and the expected one re-requested. The station ends a complete
   download with MISSION_ACK ACCEPTED (the vehicle does not need it).
5. A MISSION_ACK with an error from the vehicle ends any operation
   (:class:`OperationRefused`); the vehicle keeps its previous mission.
6. A downloaded item that is not one (:func:`~shared.mavlink.mission.items.item_from_message`:
   an unknown frame, a legacy x/y out of range) ends the download: the station sends
   MISSION_ACK with the refusal's result and reports :class:`DownloadInvalid`.
"""

from __future__ import annotations

import enum
from collections import deque
from dataclasses import dataclass
from typing import Any

from shared.config import MavlinkConfig
from shared.errors import LocalProtocolError
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.mission.items import (
    MissionItem,
    MissionRefusal,
    item_from_message,
    mission_result_name,
)

MISSION = mavlink.MAV_MISSION_TYPE_MISSION


class Operation(enum.Enum):
    """A mission operation of the ground station."""

    UPLOAD = "upload"
    DOWNLOAD = "download"
    CLEAR = "clear"


@dataclass(frozen=True, slots=True)
class UploadDone:
    """The vehicle accepted the uploaded mission."""

    count: int


@dataclass(frozen=True, slots=True)
class DownloadDone:
    """The vehicle's mission, in order."""

    items: tuple[MissionItem, ...]


@dataclass(frozen=True, slots=True)
class ClearDone:
    """The vehicle cleared its mission."""


@dataclass(frozen=True, slots=True)
class OperationRefused:
    """The vehicle ended the operation with an error MISSION_ACK."""

    operation: Operation
    result: int  #: the MAV_MISSION_RESULT

    @property
    def result_name(self) -> str:
        """E.g. ``"MAV_MISSION_INVALID_PARAM1"``."""
        return mission_result_name(self.result)


@dataclass(frozen=True, slots=True)
class OperationTimedOut:
    """The vehicle stopped answering; the operation was cancelled."""

    operation: Operation
    reason: str


@dataclass(frozen=True, slots=True)
class DownloadInvalid:
    """The vehicle sent an item that is not one; the download was cancelled (rule 6)."""

    refusal: MissionRefusal


MissionClientEvent = (UploadDone | DownloadDone | ClearDone | OperationRefused | OperationTimedOut
                      | DownloadInvalid)


class MissionClient:
    """The ground station's end of the mission protocol, talking to one vehicle.

    Args:
        address: this station (system id, component id), e.g. (255, 190).
        vehicle: the vehicle's autopilot component, e.g. (1, 1).
        config: timeouts and retries.
    """

    def __init__(self, address: Address, vehicle: Address,
                 config: MavlinkConfig | None = None) -> None:
        self.address = address
        self.vehicle = vehicle
        self.config = config if config is not None else MavlinkConfig()
        self._operation: Operation | None = None
        self._events: deque[MissionClientEvent] = deque()
        self._last_sent: Message | None = None
        self._deadline_ns: int | None = None
        self._retries = 0
        # upload
        self._upload_items: tuple[MissionItem, ...] = ()
        self._requested: set[int] = set()
        # download: None while waiting for MISSION_COUNT
        self._count: int | None = None
        self._received: list[MissionItem] = []

    @property
    def operation(self) -> Operation | None:
        """The operation in progress, or None when idle."""
        return self._operation

    def next_event(self) -> MissionClientEvent | None:
        """The next outcome, or None."""
        return self._events.popleft() if self._events else None

    # -- starting operations --------------------------------------------------------

    def upload(self, items: tuple[MissionItem, ...], now_ns: int) -> list[Message]:
        """Start replacing the vehicle's mission with ``items`` (empty clears it)."""
        self._start(Operation.UPLOAD)
        self._upload_items, self._requested = tuple(items), set()
        return self._send(self._message(mavlink.MAVLink_mission_count_message, len(items), MISSION),
                          now_ns, self.config.mission_timeout_ns)

    def download(self, now_ns: int) -> list[Message]:
        """Start reading the vehicle's mission."""
        self._start(Operation.DOWNLOAD)
        self._count, self._received = None, []
        return self._send(self._message(mavlink.MAVLink_mission_request_list_message, MISSION),
                          now_ns, self.config.mission_timeout_ns)

    def clear(self, now_ns: int) -> list[Message]:
        """Start clearing the vehicle's mission."""
        self._start(Operation.CLEAR)
        return self._send(self._message(mavlink.MAVLink_mission_clear_all_message, MISSION),
                          now_ns, self.config.mission_timeout_ns)

    def _start(self, operation: Operation) -> None:
        if self._operation is not None:
            raise LocalProtocolError(
                f"mission client: cannot start {operation.value} while "
                f"{self._operation.value} is in progress")
        self._operation, self._retries = operation, 0

    # -- input ----------------------------------------------------------------------

    def handle_message(self, msg: Message, now_ns: int) -> list[Message]:
        """Process one received message; return the messages to send."""
        if (self._operation is None or source_of(msg) != self.vehicle
                or not is_for(msg, self.address) or getattr(msg, "mission_type", None) != MISSION):
            return []
        if isinstance(msg, mavlink.MAVLink_mission_ack_message):
            return self._on_ack(msg)
        if self._operation is Operation.UPLOAD and isinstance(
                msg, mavlink.MAVLink_mission_request_int_message
                | mavlink.MAVLink_mission_request_message):
            return self._on_request(msg, now_ns)
        if self._operation is Operation.DOWNLOAD:
            if isinstance(msg, mavlink.MAVLink_mission_count_message) and self._count is None:
                return self._on_count(msg.count, now_ns)
            if isinstance(msg, mavlink.MAVLink_mission_item_int_message
                          | mavlink.MAVLink_mission_item_message) and self._count is not None:
                return self._on_item(msg, now_ns)
        return []

    def _on_ack(self, msg: Any) -> list[Message]:
        operation = self._operation
        assert operation is not None
        if msg.type != mavlink.MAV_MISSION_ACCEPTED:
            self._end(OperationRefused(operation, msg.type))
        elif operation is Operation.CLEAR:
            self._end(ClearDone())
        elif (operation is Operation.UPLOAD
              and len(self._requested) == len(self._upload_items)):
            self._end(UploadDone(len(self._upload_items)))
        return []

    def _on_request(self, msg: Any, now_ns: int) -> list[Message]:
        if not 0 <= msg.seq < len(self._upload_items):
            return []
        self._requested.add(msg.seq)
        self._retries = 0
        item = self._upload_items[msg.seq].to_message(msg.seq, self.vehicle)
        return self._send(item, now_ns, self.config.mission_timeout_ns)

    def _on_count(self, count: int, now_ns: int) -> list[Message]:
        self._count, self._retries = count, 0
        if count == 0:
            return self._finish_download()
        return self._request_next(now_ns)

    def _on_item(self, msg: Any, now_ns: int) -> list[Message]:
        if msg.seq == len(self._received):
            item = item_from_message(msg)
            if isinstance(item, MissionRefusal):
                self._end(DownloadInvalid(item))
                return [self._message(mavlink.MAVLink_mission_ack_message, item.result, MISSION)]
            self._received.append(item)
            self._retries = 0
            if len(self._received) == self._count:
                return self._finish_download()
        return self._request_next(now_ns)

    def _request_next(self, now_ns: int) -> list[Message]:
        request = self._message(mavlink.MAVLink_mission_request_int_message,
                                len(self._received), MISSION)
        return self._send(request, now_ns, self.config.mission_item_timeout_ns)

    def _finish_download(self) -> list[Message]:
        self._end(DownloadDone(tuple(self._received)))
        return [self._message(mavlink.MAVLink_mission_ack_message,
                              mavlink.MAV_MISSION_ACCEPTED, MISSION)]

    # -- timers ---------------------------------------------------------------------

    def get_timer(self) -> int | None:
        """When the awaited answer is overdue, ns; None when idle."""
        return self._deadline_ns

    def handle_timer(self, now_ns: int) -> list[Message]:
        """Resend the last message, or cancel after ``mission_retries`` resends (rule 2)."""
        if self._deadline_ns is None or now_ns < self._deadline_ns or self._last_sent is None:
            return []
        operation = self._operation
        assert operation is not None
        if self._retries >= self.config.mission_retries:
            self._end(OperationTimedOut(operation, f"no answer to {self._last_sent.get_type()} "
                                                   f"after {self._retries + 1} tries"))
            return [self._message(mavlink.MAVLink_mission_ack_message,
                                  mavlink.MAV_MISSION_OPERATION_CANCELLED, MISSION)]
        self._retries += 1
        timeout = (self.config.mission_item_timeout_ns
                   if isinstance(self._last_sent, mavlink.MAVLink_mission_request_int_message)
                   else self.config.mission_timeout_ns)
        return self._send(self._last_sent, now_ns, timeout)

    # -- helpers --------------------------------------------------------------------

    def _message(self, cls: Any, *fields: Any) -> Message:
        """A message of class ``cls`` addressed to the vehicle."""
        msg: Message = cls(self.vehicle.system_id, self.vehicle.component_id, *fields)
        return msg

    def _send(self, msg: Message, now_ns: int, timeout_ns: int) -> list[Message]:
        self._last_sent, self._deadline_ns = msg, now_ns + timeout_ns
        return [msg]

    def _end(self, event: MissionClientEvent) -> None:
        self._events.append(event)
        self._operation, self._last_sent, self._deadline_ns = None, None, None
