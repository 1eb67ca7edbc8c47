"""The mission protocol, vehicle side (devguide mission.md), sans-I/O.

Theory of operation
-------------------

The vehicle stores one mission (``mission_type`` 0): a tuple of
:class:`~shared.mavlink.mission.items.MissionItem`. A ground station replaces it
by an *upload*, reads it by a *download*, empties it by a *clear*::

    upload    GCS MISSION_COUNT(n) -> REQUEST_INT(0) ... ITEM_INT(n-1) -> MISSION_ACK
    download  GCS MISSION_REQUEST_LIST -> MISSION_COUNT(n); REQUEST_INT(i) -> ITEM_INT(i)
    clear     GCS MISSION_CLEAR_ALL -> MISSION_ACK       (an upload of 0 items is a clear)

Rules:

1. Messages in, messages out: :meth:`MissionServer.handle_message` takes a decoded
   pymavlink message and returns the messages to send; ``handle_timer`` does the
   same for deadlines (``get_timer``). Events for the application queue up for
   ``next_event``. Messages not addressed to this vehicle are ignored.
2. Uploads are atomic (devguide: "a new mission should be fully uploaded and
   accepted before the old mission is replaced"). The received items go to the
   application's ``validate`` hook; a :class:`MissionRefusal` is sent as the
   MISSION_ACK result, with a STATUSTEXT giving the reason, and the mission in
   force is kept (:class:`MissionRejected`). Clears pass the hook too (with no
   items), so the application can refuse to clear a mission it is running.
   Every message is checked before use: a MISSION_COUNT above ``mission_max_items``
   gets NO_SPACE, and one the application's ``admit`` hook refuses (a mission
   running) gets its refusal before any item is requested; an item that is not
   one (:func:`~shared.mavlink.mission.items.item_from_message`: an unknown frame,
   a legacy x/y that is not finite or out of range) ends the upload with its
   MISSION_RESULT (UNSUPPORTED_FRAME, INVALID_PARAM5_X...) and a STATUSTEXT
   (:class:`MissionRejected`).
3. The vehicle owns the upload's retry loop: it re-requests the expected item
   after ``mission_item_timeout_ns``, up to ``mission_retries`` times, then
   cancels (MISSION_ACK OPERATION_CANCELLED, :class:`UploadFailed`). Items out of
   order are dropped and the expected one re-requested. One upload at a time: a
   MISSION_COUNT from another station meanwhile gets MAV_MISSION_DENIED; from the
   same station it restarts the upload.
4. The final ACK can be lost; the station then resends the last item. While idle,
   that item gets the same ACK again. Other stray items are ignored (a late
   duplicate must not fail a station whose upload succeeded).
5. Downloads are stateless: any MISSION_REQUEST(_INT) is answered with the item,
   in any order and as often as asked (MAVProxy keeps five requests in flight).
   The deprecated MISSION_REQUEST is answered with MISSION_ITEM_INT (devguide).
6. Only the mission plan type is stored. Fence and rally requests get
   MAV_MISSION_UNSUPPORTED; a clear of MAV_MISSION_TYPE_ALL clears the mission.
7. Progress is the application's to report: :meth:`set_current` (also reached by
   MISSION_SET_CURRENT), :meth:`item_reached` and :meth:`current_message` for the
   1 Hz MISSION_CURRENT stream.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from shared.config import MavlinkConfig
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.mission.items import (
    MissionItem,
    MissionRefusal,
    item_from_message,
    mission_result_name,
)
from shared.mavlink.statustext import statustext_messages

#: Validation hook: None accepts the items, a refusal keeps the old mission.
Validator = Callable[[tuple[MissionItem, ...]], MissionRefusal | None]
#: Admission hook, asked before an upload starts: None lets it start, a refusal answers it.
Admission = Callable[[], MissionRefusal | None]

MISSION = mavlink.MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True, slots=True)
class MissionUploaded:
    """A new mission is in force (current item 0, not started)."""

    items: tuple[MissionItem, ...]
    source: Address

    def __str__(self) -> str:
        return (f"mission of {len(self.items)} item(s) uploaded by "
                f"{self.source.system_id}/{self.source.component_id}")


@dataclass(frozen=True, slots=True)
class MissionCleared:
    """The mission was cleared (MISSION_CLEAR_ALL or an upload of 0 items)."""

    source: Address

    def __str__(self) -> str:
        return f"mission cleared by {self.source.system_id}/{self.source.component_id}"


@dataclass(frozen=True, slots=True)
class MissionRejected:
    """A mission, a clear or an upload's item was refused (rule 2); the old mission stays.

    ``items`` are those received (for an item refused, the ones before it).
    """

    refusal: MissionRefusal
    items: tuple[MissionItem, ...]
    source: Address


@dataclass(frozen=True, slots=True)
class UploadFailed:
    """An upload stopped before its last item (timeout or cancelled); nothing changed."""

    reason: str
    source: Address


@dataclass(frozen=True, slots=True)
class CurrentSet:
    """The ground station set the current item (MISSION_SET_CURRENT)."""

    seq: int


MissionEvent = MissionUploaded | MissionCleared | MissionRejected | UploadFailed | CurrentSet


class _Upload:
    """An upload in progress."""

    def __init__(self, partner: Address, count: int) -> None:
        self.partner = partner
        self.count = count
        self.items: list[MissionItem] = []
        self.deadline_ns = 0  # set by each request
        self.retries = 0
        self.legacy = False  # the station sends MISSION_ITEM: request with MISSION_REQUEST


class MissionServer:
    """The vehicle's end of the mission protocol.

    Args:
        address: this vehicle (system id, component id), for filtering requests.
        config: timeouts, retries and the item limit.
        validate: called with the complete items of every upload (and ``()`` for a
            clear); returns None to accept or a :class:`MissionRefusal`.
        admit: called on a MISSION_COUNT of a new upload, before any item is requested;
            returns None to go on or a :class:`MissionRefusal` to answer it with.
    """

    def __init__(self, address: Address, config: MavlinkConfig | None = None,
                 validate: Validator | None = None, admit: Admission | None = None) -> None:
        self.address = address
        self.config = config if config is not None else MavlinkConfig()
        self._validate = validate
        self._admit = admit
        self._items: tuple[MissionItem, ...] = ()
        self._current = 0
        self._run_state = mavlink.MISSION_STATE_NOT_STARTED
        self._upload: _Upload | None = None
        self._last_ack: tuple[Address, int, int] | None = None  # partner, count, result
        self._events: deque[MissionEvent] = deque()
        self._notice_id = 0

    # -- state ----------------------------------------------------------------

    @property
    def items(self) -> tuple[MissionItem, ...]:
        """The mission in force."""
        return self._items

    @property
    def current_seq(self) -> int:
        """The current item (the goal being driven to, or the next one)."""
        return self._current

    @property
    def mission_state(self) -> int:
        """``MISSION_STATE``: NO_MISSION when empty, else what :meth:`set_run_state` said."""
        return mavlink.MISSION_STATE_NO_MISSION if not self._items else self._run_state

    def set_run_state(self, state: int) -> None:
        """Record the mission's ``MISSION_STATE`` (NOT_STARTED, ACTIVE, PAUSED, COMPLETE)."""
        self._run_state = state

    def next_event(self) -> MissionEvent | None:
        """The next event for the application, or None."""
        return self._events.popleft() if self._events else None

    # -- progress (application -> ground) ---------------------------------------

    def current_message(self) -> mavlink.MAVLink_mission_current_message:
        """MISSION_CURRENT to stream at about 1 Hz (seq, total, mission_state)."""
        return mavlink.MAVLink_mission_current_message(
            self._current, len(self._items), self.mission_state)

    def set_current(self, seq: int) -> bool:
        """Make ``seq`` the current item; False (nothing changes) if out of range.

        The caller broadcasts :meth:`current_message` after a success (devguide).
        """
        if not 0 <= seq < len(self._items):
            return False
        self._current = seq
        return True

    def item_reached(self, seq: int) -> list[Message]:
        """Report item ``seq`` reached: MISSION_ITEM_REACHED, and MISSION_CURRENT when
        the current item moves on to ``seq + 1``."""
        out: list[Message] = [mavlink.MAVLink_mission_item_reached_message(seq)]
        if seq == self._current and seq + 1 < len(self._items):
            self._current = seq + 1
            out.append(self.current_message())
        return out

    # -- input --------------------------------------------------------------------

    def handle_message(self, msg: Message, now_ns: int) -> list[Message]:
        """Process one received message; return the messages to send."""
        if not is_for(msg, self.address):
            return []
        handler = self._HANDLERS.get(type(msg))
        return handler(self, msg, now_ns) if handler is not None else []

    def _on_count(self, msg: Any, now_ns: int) -> list[Message]:
        source = source_of(msg)
        if msg.mission_type != MISSION:
            return [self._ack(source, mavlink.MAV_MISSION_UNSUPPORTED, msg.mission_type)]
        if self._upload is not None and self._upload.partner != source:
            return [self._ack(source, mavlink.MAV_MISSION_DENIED)]
        if msg.count > self.config.mission_max_items:
            self._upload = None
            return [self._ack(source, mavlink.MAV_MISSION_NO_SPACE)]
        self._last_ack = None
        if msg.count == 0:
            self._upload = None
            return self._finish(source, ())
        refusal = self._admit() if self._admit is not None else None
        if refusal is not None:
            self._upload = None
            return self._refuse(source, refusal, ())
        self._upload = _Upload(source, msg.count)
        return [self._request(self._upload, now_ns)]

    def _on_item(self, msg: Any, now_ns: int) -> list[Message]:
        source, upload = source_of(msg), self._upload
        if msg.mission_type != MISSION:
            return []
        if upload is None or upload.partner != source:
            last = self._last_ack
            if upload is None and last is not None and last[:2] == (source, msg.seq + 1):
                return [self._ack(source, last[2])]  # rule 4: our final ACK was lost
            return []
        if isinstance(msg, mavlink.MAVLink_mission_item_message):
            upload.legacy = True
        if msg.seq != len(upload.items):
            return [self._request(upload, now_ns)]
        item = item_from_message(msg)
        if isinstance(item, MissionRefusal):
            self._upload = None
            return self._refuse(source, item, tuple(upload.items))
        upload.items.append(item)
        upload.retries = 0
        if len(upload.items) < upload.count:
            return [self._request(upload, now_ns)]
        self._upload = None
        return self._finish(source, tuple(upload.items))

    def _on_request(self, msg: Any, now_ns: int) -> list[Message]:
        source = source_of(msg)
        if msg.mission_type != MISSION:
            return [self._ack(source, mavlink.MAV_MISSION_UNSUPPORTED, msg.mission_type)]
        if not 0 <= msg.seq < len(self._items):
            return [self._ack(source, mavlink.MAV_MISSION_INVALID_SEQUENCE)]
        return [self._items[msg.seq].to_message(msg.seq, source, msg.seq == self._current)]

    def _on_request_list(self, msg: Any, now_ns: int) -> list[Message]:
        source = source_of(msg)
        if msg.mission_type != MISSION:
            return [self._ack(source, mavlink.MAV_MISSION_UNSUPPORTED, msg.mission_type)]
        return [mavlink.MAVLink_mission_count_message(
            source.system_id, source.component_id, len(self._items), MISSION)]

    def _on_clear_all(self, msg: Any, now_ns: int) -> list[Message]:
        source = source_of(msg)
        if msg.mission_type not in (MISSION, mavlink.MAV_MISSION_TYPE_ALL):
            return [self._ack(source, mavlink.MAV_MISSION_UNSUPPORTED, msg.mission_type)]
        if self._upload is not None:
            if self._upload.partner != source:
                return [self._ack(source, mavlink.MAV_MISSION_DENIED, msg.mission_type)]
            self._fail_upload("cleared by the ground station")
        self._last_ack = None
        return self._finish(source, (), msg.mission_type)

    def _on_ack(self, msg: Any, now_ns: int) -> list[Message]:
        upload = self._upload
        if (upload is not None and upload.partner == source_of(msg)
                and msg.mission_type == MISSION and msg.type != mavlink.MAV_MISSION_ACCEPTED):
            self._fail_upload(f"cancelled by the ground station ({mission_result_name(msg.type)})")
        return []

    def _on_set_current(self, msg: Any, now_ns: int) -> list[Message]:
        if not self.set_current(msg.seq):
            return self._notice(f"mission: no item {msg.seq} ({len(self._items)} items)")
        self._events.append(CurrentSet(msg.seq))
        return [self.current_message()]

    _HANDLERS: ClassVar[dict[type, Callable[[MissionServer, Any, int], list[Message]]]] = {
        mavlink.MAVLink_mission_count_message: _on_count,
        mavlink.MAVLink_mission_item_int_message: _on_item,
        mavlink.MAVLink_mission_item_message: _on_item,
        mavlink.MAVLink_mission_request_int_message: _on_request,
        mavlink.MAVLink_mission_request_message: _on_request,
        mavlink.MAVLink_mission_request_list_message: _on_request_list,
        mavlink.MAVLink_mission_clear_all_message: _on_clear_all,
        mavlink.MAVLink_mission_ack_message: _on_ack,
        mavlink.MAVLink_mission_set_current_message: _on_set_current,
    }

    # -- timers -------------------------------------------------------------------

    def get_timer(self) -> int | None:
        """When the expected upload item is overdue, ns; None when no upload runs."""
        return self._upload.deadline_ns if self._upload is not None else None

    def handle_timer(self, now_ns: int) -> list[Message]:
        """Re-request an overdue item, or cancel the upload after ``mission_retries``."""
        upload = self._upload
        if upload is None or now_ns < upload.deadline_ns:
            return []
        if upload.retries >= self.config.mission_retries:
            self._fail_upload(f"no item {len(upload.items)} of {upload.count} after "
                              f"{upload.retries + 1} requests")
            return [self._ack(upload.partner, mavlink.MAV_MISSION_OPERATION_CANCELLED)]
        upload.retries += 1
        return [self._request(upload, now_ns)]

    # -- helpers ------------------------------------------------------------------

    def _request(self, upload: _Upload, now_ns: int) -> Message:
        upload.deadline_ns = now_ns + self.config.mission_item_timeout_ns
        seq, partner = len(upload.items), upload.partner
        cls = (mavlink.MAVLink_mission_request_message if upload.legacy
               else mavlink.MAVLink_mission_request_int_message)
        return cls(partner.system_id, partner.component_id, seq, MISSION)

    def _ack(self, target: Address, result: int,
             mission_type: int = MISSION) -> mavlink.MAVLink_mission_ack_message:
        return mavlink.MAVLink_mission_ack_message(
            target.system_id, target.component_id, result, mission_type)

    def _finish(self, source: Address, items: tuple[MissionItem, ...],
                mission_type: int = MISSION) -> list[Message]:
        """Validate a complete upload (or a clear), install it, and ACK (rule 2)."""
        refusal = self._validate(items) if self._validate is not None else None
        if refusal is not None:
            result = refusal.result
            out = self._refuse(source, refusal, items, mission_type)
        else:
            result = mavlink.MAV_MISSION_ACCEPTED
            self._items, self._current = items, 0
            self._run_state = mavlink.MISSION_STATE_NOT_STARTED
            self._events.append(MissionUploaded(items, source) if items
                                else MissionCleared(source))
            out = [self._ack(source, result, mission_type)]
        if items:
            self._last_ack = (source, len(items), result)
        return out

    def _refuse(self, source: Address, refusal: MissionRefusal, items: tuple[MissionItem, ...],
                mission_type: int = MISSION) -> list[Message]:
        """Answer an upload, an item or a clear with ``refusal`` (rule 2)."""
        self._events.append(MissionRejected(refusal, items, source))
        return [self._ack(source, refusal.result, mission_type),
                *self._notice(f"mission refused: {refusal.reason}")]

    def _fail_upload(self, reason: str) -> None:
        assert self._upload is not None
        self._events.append(UploadFailed(reason, self._upload.partner))
        self._upload = None

    def _notice(self, text: str) -> list[Message]:
        self._notice_id = self._notice_id % 0xFFFF + 1
        return statustext_messages(mavlink.MAV_SEVERITY_WARNING, text, self._notice_id)
