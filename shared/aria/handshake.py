"""The SYNC handshake packets (reference §3).

The host sends SYNC0, SYNC1, SYNC2: packets with IDs 0, 1, 2 and no data. The robot
echoes SYNC0 and SYNC1, and answers SYNC2 with ID 2 followed by three NUL-terminated
strings: its name, class and subclass (``FA FB 19 02 "vmnav\\0" "Pioneer\\0"
"p3at-sh\\0" 2A 56``). ARIA picks its parameter file from the lower-cased subclass,
so the subclass and the DistConvFactor of the positions must agree (reference §8:
``p3at`` means 0.465 mm per count, ``p3at-sh`` 1.0).

IDs 0-2 double as PULSE, OPEN and CLOSE once the handshake is over; which one a
packet is depends on the connection state (``state.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.aria._wire import TEXT_ENCODING, encode_cstring
from shared.aria.framing import Packet
from shared.errors import LocalProtocolError, RemoteProtocolError


@dataclass(frozen=True, slots=True)
class SyncRequest:
    """SYNC0/1/2 from the host (ID = ``seq``, no data).

    Attributes:
        seq: 0, 1 or 2.
    """

    seq: int

    def __post_init__(self) -> None:
        if self.seq not in (0, 1, 2):
            raise LocalProtocolError(f"SyncRequest seq must be 0, 1 or 2, got {self.seq!r}")

    def to_packet(self) -> Packet:
        return Packet(self.seq)


@dataclass(frozen=True, slots=True)
class SyncReply:
    """The robot's echo of SYNC0 or SYNC1 (SYNC2 is answered by :class:`RobotIdentity`).

    Attributes:
        seq: 0 or 1.
    """

    seq: int

    def __post_init__(self) -> None:
        if self.seq not in (0, 1):
            raise LocalProtocolError(
                f"SyncReply seq must be 0 or 1 (RobotIdentity answers SYNC2), got {self.seq!r}"
            )

    def to_packet(self) -> Packet:
        return Packet(self.seq)


@dataclass(frozen=True, slots=True)
class RobotIdentity:
    """The robot's SYNC2 reply: ID 2, then name, class and subclass, each NUL-terminated.

    Attributes:
        name: the robot's name (MobileSim sends ``"MobileSim"``, which ARIA takes as a
            simulator).
        robot_class: ``"Pioneer"`` for every Pioneer.
        subclass: ARIA's parameter set, e.g. ``"p3at-sh"`` (DistConvFactor 1.0) or
            ``"p3at"`` (0.465).

    Raises:
        LocalProtocolError: a string holds a NUL or a character outside Latin-1.
    """

    name: str = "vmnav"
    robot_class: str = "Pioneer"
    subclass: str = "p3at-sh"

    def __post_init__(self) -> None:
        self.to_packet()  # validates the strings

    def to_packet(self) -> Packet:
        parts = []
        for label, text in (("name", self.name), ("robot_class", self.robot_class),
                            ("subclass", self.subclass)):
            parts.append(encode_cstring(f"RobotIdentity.{label}", text))
        return Packet(2, b"".join(parts))

    @classmethod
    def from_packet(cls, packet: Packet) -> RobotIdentity:
        """Decode a SYNC2 reply.

        Raises:
            RemoteProtocolError: the ID is not 2, or the data is not three NUL-terminated strings.
        """
        if packet.packet_id != 2:
            raise RemoteProtocolError(f"SYNC2 reply has ID {packet.packet_id}, not 2")
        fields = packet.data.split(b"\0")
        if len(fields) != 4 or fields[3]:
            raise RemoteProtocolError(
                f"SYNC2 reply data {packet.data!r} is not three NUL-terminated strings"
            )
        name, robot_class, subclass = (f.decode(TEXT_ENCODING) for f in fields[:3])
        return cls(name, robot_class, subclass)

