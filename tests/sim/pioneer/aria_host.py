"""An ARIA-like client for the tests: a host-role AriaSession on a byte link, in the test's time."""

from __future__ import annotations

from shared.aria import (
    AriaSession,
    ClientCommand,
    Command,
    ConfigPacket,
    ConnState,
    Event,
    RobotIdentity,
    Role,
    Sendable,
    Sip,
    SipType,
    SyncReply,
    SyncRequest,
    UnexpectedPacket,
)
from shared.byte_link import ByteLink

RESYNC_DELAY_NS = 200_000_000
"""After CLOSE to a stale session, wait this long for its SIPs to stop before SYNC0, ns."""


class AriaHost:
    """Connects as stock ARIA does (reference §3) and records what the robot sends.

    * ``connect``: SYNC0; each echo -> the next SYNC; the identity -> OPEN 1 and CONFIG 1
      (``open_on_identity = False`` makes a client that never opens).
    * A 0x32 SIP in answer to SYNC0 (a stale session): CLOSE 1, then SYNC0 once the
      stream has had :data:`RESYNC_DELAY_NS` to stop (ARIA's recovery).
    * ``keepalive``: run the session timers (PULSE after 500 ms idle); False is a client
      gone silent.

    Args:
        link: the client end of the link.
    """

    def __init__(self, link: ByteLink, open_on_identity: bool = True) -> None:
        self.link = link
        self.session = AriaSession(Role.HOST)
        self.open_on_identity = open_on_identity
        self.keepalive = True
        self.events: list[Event] = []
        self.sips: list[tuple[int, Sip]] = []
        """(arrival time ns, SIP)."""
        self.configs: list[ConfigPacket] = []
        self.stale_closes = 0
        self._resync_at_ns: int | None = None

    def send(self, event: Sendable, now_ns: int) -> None:
        self.link.write(self.session.send(event, now_ns))

    def command(self, command: Command, arg: int | None, now_ns: int) -> None:
        self.send(ClientCommand(command, arg), now_ns)

    def connect(self, now_ns: int) -> None:
        self.send(SyncRequest(0), now_ns)

    def poll(self, now_ns: int) -> None:
        """Read what arrived, react, and (with keepalive) run the timers."""
        self.session.receive_data(self.link.read_available(), now_ns)
        self._drain(now_ns)
        if self._resync_at_ns is not None and now_ns >= self._resync_at_ns:
            self._resync_at_ns = None
            self.send(SyncRequest(0), now_ns)
        deadline = self.session.get_timer()
        if self.keepalive and deadline is not None and now_ns >= deadline:
            self.link.write(self.session.handle_timer(now_ns))
            self._drain(now_ns)

    def _drain(self, now_ns: int) -> None:
        while (event := self.session.next_event()) is not None:
            self.events.append(event)
            if isinstance(event, SyncReply):
                self.send(SyncRequest(event.seq + 1), now_ns)
            elif isinstance(event, RobotIdentity) and self.open_on_identity:
                self.command(Command.OPEN, 1, now_ns)
                self.command(Command.CONFIG, 1, now_ns)
            elif isinstance(event, Sip):
                self.sips.append((now_ns, event))
            elif isinstance(event, ConfigPacket):
                self.configs.append(event)
            elif (isinstance(event, UnexpectedPacket)
                  and event.packet.packet_id == SipType.STOPPED
                  and self.session.state is ConnState.SYNC0_REQUESTED):
                self.stale_closes += 1
                self.command(Command.CLOSE, 1, now_ns)
                self._resync_at_ns = now_ns + RESYNC_DELAY_NS
