"""One ARIA conversation, sans-I/O, in either role (h11-style surface).

Usage (host; the robot role is symmetric)::

    session = AriaSession(Role.HOST, AriaLinkConfig())
    transport.write(session.send(SyncRequest(0), clock.now_ns()))
    ...
    session.receive_data(transport.read(), clock.now_ns())
    while (event := session.next_event()) is not None:
        ...                                   # SyncReply(0) -> send SyncRequest(1), ...
    if (deadline := session.get_timer()) is not None and clock.now_ns() >= deadline:
        transport.write(session.handle_timer(clock.now_ns()))

Rules:

1. Bytes in, events out, bytes out; no I/O and no clock. Time arrives as ``now_ns``
   with the data it stamps (``receive_data``, ``send``, ``handle_timer``), because the
   timers key on when things were sent and received.
2. Received bytes are deframed at once but decoded lazily, one packet per
   ``next_event`` call, in the state that packet finds: IDs 0-2 mean different
   things before and after OPEN (``state.py``).
3. Nothing received is fatal: bad checksums come out as ``CorruptPacket``, packets
   that do not fit as ``UnexpectedPacket``.
4. Timer policy comes from :class:`~shared.config.AriaLinkConfig`. ``handle_timer``
   returns the bytes a timer sends (the host's SYNC0 retry and PULSE) and queues the
   timer events (``ConnectFailed``, ``LinkLost``, ``WatchdogExpired``, ``SipDue``).
   It is safe to call early; it does only what is due.
5. The application answers the handshake itself: the robot sends ``SyncReply(n)`` on
   ``SyncRequest(n)`` and its :class:`RobotIdentity` on ``SyncRequest(2)``; the host
   sends the next ``SyncRequest`` on each reply and ``OPEN`` on the identity.
"""

from __future__ import annotations

from collections import deque

from shared.aria.commands import ClientCommand, Command
from shared.aria.config_packet import CONFIG_PACKET_ID, ConfigPacket
from shared.aria.events import (
    ConnectFailed,
    Event,
    LinkLost,
    RawPacket,
    Sendable,
    SipDue,
    UnexpectedPacket,
    WatchdogCleared,
    WatchdogExpired,
)
from shared.aria.framing import CorruptPacket, Packet, PacketBuffer
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.sip import ENCODER_PACKET_ID, EncoderPacket, Sip, SipType
from shared.aria.state import (
    HANDSHAKE_STATES,
    OPEN_STATES,
    REQUESTED_STATES,
    TRANSITIONS,
    ConnState,
    Role,
    event_kind,
)
from shared.config import AriaLinkConfig
from shared.errors import LocalProtocolError, RemoteProtocolError


class AriaSession:
    """One end of an ARIA link.

    Args:
        role: HOST (client) or ROBOT (server).
        config: timing policy; defaults to ARIA's and ARCOS's values.
    """

    def __init__(self, role: Role, config: AriaLinkConfig | None = None) -> None:
        self.role = role
        self.config = config if config is not None else AriaLinkConfig()
        self._peer = Role.ROBOT if role is Role.HOST else Role.HOST
        self._state = ConnState.WAIT_SYNC0
        self._buffer = PacketBuffer()
        self._frames: deque[Packet | CorruptPacket] = deque()  # deframed, not yet decoded
        self._events: deque[Event] = deque()  # decoded or timer events, ready to return
        self._identity: RobotIdentity | None = None
        self._last_feed_ns: int | None = None
        self._last_send_ns = 0
        self._last_packet_ns = 0
        # Host timers.
        self._sync_deadline_ns: int | None = None
        self._sync0_sent = 0
        self._last_sip_ns = 0
        # Robot timers.
        self._next_sip_ns = 0
        self._watchdog_tripped = False

    # -- state and counters ---------------------------------------------------

    @property
    def state(self) -> ConnState:
        """The connection state as this end sees it."""
        return self._state

    @property
    def identity(self) -> RobotIdentity | None:
        """The robot's SYNC2 reply: received (host) or sent (robot); None before."""
        return self._identity

    @property
    def bad_checksums(self) -> int:
        """Received frames that failed their checksum."""
        return self._buffer.bad_checksums

    @property
    def skipped_bytes(self) -> int:
        """Received bytes discarded while hunting for a frame header."""
        return self._buffer.skipped_bytes

    @property
    def abandoned_frames(self) -> int:
        """Partial frames dropped after the frame timeout."""
        return self._buffer.abandoned_frames

    # -- receiving --------------------------------------------------------------

    def receive_data(self, data: bytes, now_ns: int) -> None:
        """Feed bytes from the link, in any chunking.

        Args:
            data: received bytes; empty is a no-op (serial links have no end of
                stream; on a TCP close the adapter discards the session).
            now_ns: when they arrived, ns.
        """
        if data:
            self._buffer.feed(data)
            self._last_feed_ns = now_ns

    def next_event(self) -> Event | None:
        """The next event, or ``None`` until more data arrives or a timer fires."""
        if self._events:
            return self._events.popleft()
        frame = self._frames.popleft() if self._frames else self._buffer.next_frame()
        if frame is None or isinstance(frame, CorruptPacket):
            return frame
        return self._receive_packet(frame)

    def _receive_packet(self, packet: Packet) -> Event:
        now_ns = self._last_feed_ns if self._last_feed_ns is not None else 0
        self._last_packet_ns = now_ns
        event = self._decode(packet)
        if not isinstance(event, UnexpectedPacket):
            target = TRANSITIONS[self._state].get((self._peer, event_kind(event)))
            if target is None:
                event = UnexpectedPacket(
                    packet, f"{type(event).__name__} not expected in state {self._state.name}"
                )
            else:
                self._enter(target, now_ns)
                if isinstance(event, Sip):
                    self._last_sip_ns = now_ns
                elif isinstance(event, RobotIdentity):
                    self._identity = event
        if (isinstance(event, UnexpectedPacket) and self.role is Role.ROBOT
                and self._state in HANDSHAKE_STATES):
            self._enter(ConnState.WAIT_SYNC0, now_ns)
        if self._watchdog_tripped:
            self._watchdog_tripped = False
            self._events.append(event)
            return WatchdogCleared()
        return event

    def _decode(self, packet: Packet) -> Event:
        """Decode a received packet in the current state (rule 2)."""
        pid, data, state = packet.packet_id, packet.data, self._state
        try:
            if self.role is Role.ROBOT:
                if pid <= 2 and not data and state in HANDSHAKE_STATES:
                    return SyncRequest(pid)
                if pid == 0 and not data and state in (ConnState.CONNECTED, ConnState.CLOSED):
                    return SyncRequest(0)
                return ClientCommand.from_packet(packet)
            if state in HANDSHAKE_STATES:
                if pid <= 1 and not data:
                    return SyncReply(pid)
                if pid == 2:
                    return RobotIdentity.from_packet(packet)
            if pid in tuple(SipType):
                return Sip.from_packet(packet)
            if pid == CONFIG_PACKET_ID:
                return ConfigPacket.from_packet(packet)
            if pid == ENCODER_PACKET_ID:
                return EncoderPacket.from_packet(packet)
            return RawPacket(pid, data)
        except (RemoteProtocolError, LocalProtocolError) as e:  # constructors validate too
            return UnexpectedPacket(packet, f"malformed in state {state.name}: {e}")

    # -- sending ----------------------------------------------------------------

    def send(self, event: Sendable, now_ns: int) -> bytes:
        """Encode ``event`` and apply it to the state.

        Args:
            event: an event this role may send in this state.
            now_ns: when the bytes go out, ns.

        Returns:
            The bytes to write to the link.

        Raises:
            LocalProtocolError: the event is illegal for this role in this state (the
                message names both), or a value does not fit its wire field.
        """
        target = TRANSITIONS[self._state].get((self.role, event_kind(event)))
        if target is None:
            raise LocalProtocolError(
                f"{self.role.name} cannot send {event!r} in state {self._state.name}"
            )
        data = event.to_packet().to_bytes()
        self._last_send_ns = now_ns
        if isinstance(event, SyncRequest):
            self._sync_deadline_ns = now_ns + self.config.sync_reply_timeout_ns
            if event.seq == 0:
                self._sync0_sent += 1
        elif isinstance(event, RobotIdentity):
            self._identity = event
        self._enter(target, now_ns)
        return data

    def _enter(self, target: ConnState, now_ns: int) -> None:
        if target in OPEN_STATES and self._state not in OPEN_STATES:
            self._last_sip_ns = now_ns
            self._last_packet_ns = now_ns
            self._next_sip_ns = now_ns
            self._watchdog_tripped = False
        if target not in REQUESTED_STATES:
            self._sync_deadline_ns = None
        if target in (ConnState.CONNECTED, ConnState.CLOSED):
            self._sync0_sent = 0
        self._state = target

    def _apply_own(self, event: ConnectFailed | LinkLost, now_ns: int) -> None:
        """Queue a timer event of our own role and take its transition."""
        self._events.append(event)
        self._enter(TRANSITIONS[self._state][(self.role, event_kind(event))], now_ns)

    # -- timers -------------------------------------------------------------------

    def get_timer(self) -> int | None:
        """The earliest deadline at which :meth:`handle_timer` has work, ns; None if none."""
        cfg, deadlines = self.config, []
        if self._buffer.pending_bytes and self._last_feed_ns is not None:
            deadlines.append(self._last_feed_ns + cfg.frame_timeout_ns)
        if self.role is Role.HOST:
            if self._state in REQUESTED_STATES and self._sync_deadline_ns is not None:
                deadlines.append(self._sync_deadline_ns)
            if self._state in OPEN_STATES:
                deadlines.append(self._last_send_ns + cfg.pulse_period_ns)
                deadlines.append(self._last_sip_ns + cfg.link_timeout_ns)
        elif self._state in OPEN_STATES:
            deadlines.append(self._next_sip_ns)
            if not self._watchdog_tripped:
                deadlines.append(self._last_packet_ns + cfg.watchdog_timeout_ns)
        return min(deadlines) if deadlines else None

    def handle_timer(self, now_ns: int) -> bytes:
        """Do what is due at ``now_ns``: queue timer events, return bytes to send.

        Host: resend SYNC0 when a SYNC reply is overdue, or fail after
        ``sync_attempts`` SYNC0s (``ConnectFailed``); while open, send PULSE after
        ``pulse_period_ns`` without sending, and give up after ``link_timeout_ns``
        without a SIP (``LinkLost``). Robot: while open, ``SipDue`` every
        ``sip_period_ns`` and ``WatchdogExpired`` after ``watchdog_timeout_ns``
        without a client packet. Both: abandon a partial frame after
        ``frame_timeout_ns`` without a new byte.

        Returns:
            Bytes to write (possibly empty).
        """
        self._expire_partial_frame(now_ns)
        if self.role is Role.HOST:
            return self._host_timers(now_ns)
        self._robot_timers(now_ns)
        return b""

    def _expire_partial_frame(self, now_ns: int) -> None:
        last = self._last_feed_ns
        if last is None or now_ns < last + self.config.frame_timeout_ns:
            return
        while True:
            while (frame := self._buffer.next_frame()) is not None:
                self._frames.append(frame)
            if not self._buffer.pending_bytes:
                return
            self._buffer.abandon_partial()

    def _host_timers(self, now_ns: int) -> bytes:
        cfg = self.config
        if (self._state in REQUESTED_STATES and self._sync_deadline_ns is not None
                and now_ns >= self._sync_deadline_ns):
            if self._sync0_sent >= cfg.sync_attempts:
                self._apply_own(ConnectFailed(self._sync0_sent), now_ns)
                return b""
            return self.send(SyncRequest(0), now_ns)
        if self._state in OPEN_STATES:
            if now_ns >= self._last_sip_ns + cfg.link_timeout_ns:
                self._apply_own(LinkLost(now_ns - self._last_sip_ns), now_ns)
                return b""
            if now_ns >= self._last_send_ns + cfg.pulse_period_ns:
                return self.send(ClientCommand(Command.PULSE), now_ns)
        return b""

    def _robot_timers(self, now_ns: int) -> None:
        if self._state not in OPEN_STATES:
            return
        cfg = self.config
        silence_ns = now_ns - self._last_packet_ns
        if not self._watchdog_tripped and silence_ns >= cfg.watchdog_timeout_ns:
            self._watchdog_tripped = True
            self._events.append(WatchdogExpired(silence_ns))
        if now_ns >= self._next_sip_ns:
            self._events.append(SipDue(self._next_sip_ns))
            self._next_sip_ns += cfg.sip_period_ns
            if self._next_sip_ns <= now_ns:  # more than a cycle late: re-anchor, no burst
                self._next_sip_ns = now_ns + cfg.sip_period_ns
