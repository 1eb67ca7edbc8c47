"""Session events that are not packets of a codec module, and the :data:`Event` union.

Packet events live with their codecs: :class:`~shared.aria.handshake.SyncRequest`,
:class:`~shared.aria.handshake.SyncReply`, :class:`~shared.aria.handshake.RobotIdentity`,
:class:`~shared.aria.commands.ClientCommand`, :class:`~shared.aria.sip.Sip`,
:class:`~shared.aria.sip.EncoderPacket`, :class:`~shared.aria.config_packet.ConfigPacket`
and :class:`~shared.aria.framing.CorruptPacket`. This module adds the raw packet, the
diagnostic for a packet that does not fit the conversation, and the timer events.
Cores return diagnostics as data: nothing here logs.
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.aria.commands import ClientCommand
from shared.aria.config_packet import ConfigPacket
from shared.aria.framing import CorruptPacket, Packet
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.sip import EncoderPacket, Sip


@dataclass(frozen=True, slots=True)
class RawPacket:
    """A robot packet this codec does not decode (IOpac 0xF0, GYROpac 0x98, SIMSTAT 0x62,
    the 0xFF/0xFE reset notice, ...), or one a robot sends as is.

    Attributes:
        packet_id: the ID byte.
        data: the DATA bytes.
    """

    packet_id: int
    data: bytes = b""

    def __post_init__(self) -> None:
        self.to_packet()  # validates ID and length

    def to_packet(self) -> Packet:
        return Packet(self.packet_id, self.data)


@dataclass(frozen=True, slots=True)
class UnexpectedPacket:
    """A well-framed packet that does not fit the conversation; it changed nothing.

    A robot session in the handshake also restarts at SYNC0 (reference §3: the
    specification's answer to an out-of-sequence SYNC).

    Attributes:
        packet: what arrived.
        reason: why it was not taken, naming the state.
    """

    packet: Packet
    reason: str


@dataclass(frozen=True, slots=True)
class WatchdogExpired:
    """Robot role: no client packet for the watchdog time while open.

    ARCOS stops the robot (and resumes the last motion when packets return);
    MobileSim only warns. The emulator chooses.

    Attributes:
        silence_ns: time since the last client packet, ns.
    """

    silence_ns: int


@dataclass(frozen=True, slots=True)
class WatchdogCleared:
    """Robot role: a client packet arrived after :class:`WatchdogExpired`."""


@dataclass(frozen=True, slots=True)
class SipDue:
    """Robot role: the next SIP cycle has come; the application sends a :class:`Sip`.

    Attributes:
        deadline_ns: the cycle's scheduled time, ns (the SIP grid, not the call time).
    """

    deadline_ns: int


@dataclass(frozen=True, slots=True)
class ConnectFailed:
    """Host role: no complete handshake after the configured SYNC0 attempts; state CLOSED.

    Attributes:
        attempts: SYNC0 packets sent in this connection attempt.
    """

    attempts: int


@dataclass(frozen=True, slots=True)
class LinkLost:
    """Host role: no SIP for the link timeout while open; state CLOSED.

    Attributes:
        silence_ns: time since the last SIP (or since OPEN), ns.
    """

    silence_ns: int


Sendable = (
    SyncRequest | SyncReply | RobotIdentity | ClientCommand | Sip | EncoderPacket | ConfigPacket
    | RawPacket
)
"""Events that are packets: what :meth:`AriaSession.send` takes (the table says which, when)."""

Event = (
    SyncRequest | SyncReply | RobotIdentity | ClientCommand | Sip | EncoderPacket | ConfigPacket
    | RawPacket | CorruptPacket | UnexpectedPacket | WatchdogExpired | WatchdogCleared | SipDue
    | ConnectFailed | LinkLost
)
"""Everything :meth:`AriaSession.next_event` returns."""
