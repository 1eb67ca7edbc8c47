"""The Pioneer/ARIA client-server protocol, sans-I/O, for both ends of the link.

The robot-side driver (``robot/``) runs an :class:`AriaSession` in the HOST role; the
simulator's emulated Pioneer (``sim/``) runs one in the ROBOT role. Both feed bytes
in and get events out, and turn events into bytes; neither the codec nor the
session touches a port or a clock. The protocol is specified byte by byte in the
team's ``reference/aria-protocol.md``, cited here by section.

Modules:

* ``checksum``: the checksum, a pure function.
* ``framing``: frames, the single-frame decoder and the resyncing :class:`PacketBuffer`.
* ``commands``: the :class:`Command` opcodes, argument encoding, SI helpers.
* ``handshake``: SYNC0-2 and the robot's identity reply.
* ``sip``: the standard SIP and the ENCODERpac; ``config_packet``: the CONFIGpac.
* ``p3at``: the Pioneer 3-AT as ARIA knows it (subclass, conversion factors, sonar
  geometry), for the emulator and the robot's driver.
* ``events``: the remaining events; ``state``: the transitions table;
  ``session``: :class:`AriaSession`.
"""

from shared.aria.checksum import aria_checksum
from shared.aria.commands import (
    ArgType,
    ClientCommand,
    Command,
    DataArg,
    battest,
    dchead,
    dhead,
    enable,
    head,
    move,
    rotate,
    rvel,
    seta,
    setra,
    setrv,
    setrvdir,
    setv,
    sim_set_pose,
    vel,
    vel2,
    vel2_wheels,
)
from shared.aria.config_packet import ConfigPacket
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
from shared.aria.framing import CorruptPacket, Packet, PacketBuffer, decode_packet, encode_packet
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.session import AriaSession
from shared.aria.sip import (
    ChargeState,
    EncoderPacket,
    Sip,
    SipFlags,
    SipIo,
    SipType,
    SonarReading,
    position_delta,
    wrap_position,
)
from shared.aria.state import ConnState, Role

__all__ = [
    "ArgType",
    "AriaSession",
    "ChargeState",
    "ClientCommand",
    "Command",
    "ConfigPacket",
    "ConnState",
    "ConnectFailed",
    "CorruptPacket",
    "DataArg",
    "EncoderPacket",
    "Event",
    "LinkLost",
    "Packet",
    "PacketBuffer",
    "RawPacket",
    "RobotIdentity",
    "Role",
    "Sendable",
    "Sip",
    "SipDue",
    "SipFlags",
    "SipIo",
    "SipType",
    "SonarReading",
    "SyncReply",
    "SyncRequest",
    "UnexpectedPacket",
    "WatchdogCleared",
    "WatchdogExpired",
    "aria_checksum",
    "battest",
    "dchead",
    "decode_packet",
    "dhead",
    "enable",
    "encode_packet",
    "head",
    "move",
    "position_delta",
    "rotate",
    "rvel",
    "seta",
    "setra",
    "setrv",
    "setrvdir",
    "setv",
    "sim_set_pose",
    "vel",
    "vel2",
    "vel2_wheels",
    "wrap_position",
]
