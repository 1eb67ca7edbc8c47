"""The ARIA connection state machine: roles, states and the one transitions table.

Theory of operation
-------------------

A conversation has two parties: the HOST (ARIA, p2os, our driver) and the ROBOT
(ARCOS, MobileSim, the sim's emulated Pioneer). Each end keeps its own
:class:`~shared.aria.session.AriaSession`, and both use the table below: a session
applies its own events when it sends them and the peer's events when it receives
them, keyed by ``(sender's role, event kind)``.

Connect (reference §3)::

    WAIT_SYNC0 -host SYNC0-> SYNC0_REQUESTED -robot SYNC0 echo-> WAIT_SYNC1
    WAIT_SYNC1 -host SYNC1-> SYNC1_REQUESTED -robot SYNC1 echo-> WAIT_SYNC2
    WAIT_SYNC2 -host SYNC2-> SYNC2_REQUESTED -robot name/class/subclass-> CONNECTED
    CONNECTED  -host OPEN-> OPEN (the robot streams SIPs from here on)
    OPEN       -robot SIP with motors enabled-> RUNNING -robot SIP with motors off-> OPEN
    OPEN, RUNNING -host CLOSE-> CLOSED -host SYNC0-> SYNC0_REQUESTED (serial re-sync)

Rules:

1. A SYNC0 from the host restarts the handshake from any state before OPEN
   (resends after a timeout, a fresh client on a serial link).
2. RUNNING is what the robot *reports* (SIP FLAGS bit 0), not what the host asked:
   ARCOS refuses ENABLE while the e-stop is engaged (p2os #69).
3. IDs 0-2 are SYNC0-2 before OPEN and PULSE/OPEN/CLOSE after; so PULSE is legal
   only while open, and CONNECTED reads an ID-0 packet as a SYNC0 restart.
4. A received packet the table does not allow is reported as ``UnexpectedPacket``
   and changes nothing, except that a robot in the handshake restarts at WAIT_SYNC0
   (the specification's rule for out-of-sequence SYNCs). The host ignores it; its
   SYNC timer restarts the handshake.
5. An event the table does not allow raises ``LocalProtocolError`` on send.
6. The host may send CLOSE while waiting for SYNC0, to stop a stale robot that still
   streams SIPs (ARIA does this on a 0x32 reply, reference §3).
7. Timers are events of the session's own role: ConnectFailed (SYNC attempts used
   up) and LinkLost (no SIP for the link timeout) both end in CLOSED.
"""

from __future__ import annotations

from enum import Enum

from shared.aria.commands import ClientCommand, Command
from shared.aria.config_packet import ConfigPacket
from shared.aria.events import ConnectFailed, LinkLost, RawPacket
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.sip import EncoderPacket, Sip


class Role(Enum):
    """Which end of the link a session is."""

    HOST = "HOST"  #: the client: sends SYNCs and commands, receives SIPs
    ROBOT = "ROBOT"  #: the server: answers SYNCs, streams SIPs


class ConnState(Enum):
    """Connection states, as one end sees the conversation."""

    WAIT_SYNC0 = "WAIT_SYNC0"  #: idle; the host's turn to send SYNC0
    SYNC0_REQUESTED = "SYNC0_REQUESTED"  #: SYNC0 sent, echo pending
    WAIT_SYNC1 = "WAIT_SYNC1"  #: SYNC0 echoed; the host's turn to send SYNC1
    SYNC1_REQUESTED = "SYNC1_REQUESTED"  #: SYNC1 sent, echo pending
    WAIT_SYNC2 = "WAIT_SYNC2"  #: SYNC1 echoed; the host's turn to send SYNC2
    SYNC2_REQUESTED = "SYNC2_REQUESTED"  #: SYNC2 sent, identity pending
    CONNECTED = "CONNECTED"  #: identity received; no SIPs until OPEN
    OPEN = "OPEN"  #: SIPs stream; the robot reports its motors disabled
    RUNNING = "RUNNING"  #: SIPs stream; the robot reports its motors enabled
    CLOSED = "CLOSED"  #: CLOSE sent, connect failed or link lost


HANDSHAKE_STATES = frozenset({
    ConnState.WAIT_SYNC0, ConnState.SYNC0_REQUESTED, ConnState.WAIT_SYNC1,
    ConnState.SYNC1_REQUESTED, ConnState.WAIT_SYNC2, ConnState.SYNC2_REQUESTED,
})
REQUESTED_STATES = frozenset({
    ConnState.SYNC0_REQUESTED, ConnState.SYNC1_REQUESTED, ConnState.SYNC2_REQUESTED,
})
OPEN_STATES = frozenset({ConnState.OPEN, ConnState.RUNNING})

EventKind = tuple[type, object]
"""An event's class plus what selects its transition (a SYNC number, a command, motors on)."""


def event_kind(event: object) -> EventKind:
    """The transitions-table key of ``event`` (without the sender's role)."""
    if isinstance(event, SyncRequest | SyncReply):
        return type(event), event.seq
    if isinstance(event, ClientCommand):
        special = event.command in (Command.PULSE, Command.OPEN, Command.CLOSE)
        return ClientCommand, event.command if special else None
    if isinstance(event, Sip):
        return Sip, event.motors_enabled
    return type(event), None


Key = tuple[Role, EventKind]
"""A transitions-table key: the sender's role and the event kind."""

_HOST, _ROBOT = Role.HOST, Role.ROBOT
_SYNC: list[Key] = [(_HOST, (SyncRequest, n)) for n in (0, 1, 2)]
_ECHO: list[Key] = [(_ROBOT, (SyncReply, n)) for n in (0, 1)]
_IDENTITY: Key = (_ROBOT, (RobotIdentity, None))
_PULSE: Key = (_HOST, (ClientCommand, Command.PULSE))
_OPEN: Key = (_HOST, (ClientCommand, Command.OPEN))
_CLOSE: Key = (_HOST, (ClientCommand, Command.CLOSE))
_COMMAND: Key = (_HOST, (ClientCommand, None))
_SIP_OFF: Key = (_ROBOT, (Sip, False))
_SIP_ON: Key = (_ROBOT, (Sip, True))
_CONNECT_FAILED: Key = (_HOST, (ConnectFailed, None))
_LINK_LOST: Key = (_HOST, (LinkLost, None))

_S = ConnState
_RESTART: dict[Key, ConnState] = {_SYNC[0]: _S.SYNC0_REQUESTED}
_WHILE_OPEN: dict[Key, ConnState | None] = {
    _PULSE: None, _OPEN: None, _COMMAND: None, _SIP_OFF: _S.OPEN, _SIP_ON: _S.RUNNING,
    (_ROBOT, (EncoderPacket, None)): None, (_ROBOT, (ConfigPacket, None)): None,
    (_ROBOT, (RawPacket, None)): None, _CLOSE: _S.CLOSED, _LINK_LOST: _S.CLOSED,
}


def _stay(state: ConnState, moves: dict[Key, ConnState | None]) -> dict[Key, ConnState]:
    """``moves`` with ``None`` (stay in ``state``) filled in."""
    return {key: state if target is None else target for key, target in moves.items()}


TRANSITIONS: dict[ConnState, dict[Key, ConnState]] = {
    _S.WAIT_SYNC0: {**_RESTART, _CLOSE: _S.WAIT_SYNC0},
    _S.SYNC0_REQUESTED: {
        **_RESTART, _CLOSE: _S.WAIT_SYNC0, _ECHO[0]: _S.WAIT_SYNC1,
        _CONNECT_FAILED: _S.CLOSED,
    },
    _S.WAIT_SYNC1: {**_RESTART, _SYNC[1]: _S.SYNC1_REQUESTED},
    _S.SYNC1_REQUESTED: {
        **_RESTART, _SYNC[1]: _S.SYNC1_REQUESTED, _ECHO[1]: _S.WAIT_SYNC2,
        _CONNECT_FAILED: _S.CLOSED,
    },
    _S.WAIT_SYNC2: {**_RESTART, _SYNC[2]: _S.SYNC2_REQUESTED},
    _S.SYNC2_REQUESTED: {
        **_RESTART, _SYNC[2]: _S.SYNC2_REQUESTED, _IDENTITY: _S.CONNECTED,
        _CONNECT_FAILED: _S.CLOSED,
    },
    _S.CONNECTED: {**_RESTART, _OPEN: _S.OPEN, _CLOSE: _S.CLOSED, _COMMAND: _S.CONNECTED},
    _S.OPEN: _stay(_S.OPEN, _WHILE_OPEN),
    _S.RUNNING: _stay(_S.RUNNING, _WHILE_OPEN),
    _S.CLOSED: dict(_RESTART),
}
"""state -> {(sender's role, event kind): next state}; a missing key is illegal."""
