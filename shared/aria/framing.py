"""ARIA packet framing: a frame encoder, a single-frame decoder and a streaming deframer.

Wire format (reference §1), the same in both directions::

    +------+------+-------+------+-----------------------+--------+--------+
    | 0xFA | 0xFB | COUNT |  ID  |  DATA (COUNT-3 bytes) | CKS_HI | CKS_LO |
    +------+------+-------+------+-----------------------+--------+--------+

Byte-order quirks, all in one place:

* COUNT is the number of bytes *after* it (ID + DATA + 2 checksum bytes), and it is
  **unsigned**. ARIA before 2025 read it as a signed char and so dropped every
  packet with COUNT >= 0x80 (AriaCoda #15, fixed in c746e1a).
* Integer fields inside DATA are **little-endian** (int16 and int32 LSB first).
* Command arguments are a **sign byte** (0x3B positive, 0x1B negative) followed by
  the little-endian uint16 **magnitude**, not two's complement (``commands.py``).
* The checksum is sent **big-endian** (high byte first) and sums **big-endian**
  16-bit words (``checksum.py``).

Receiving rules (ARIA ``ArRobotPacketReceiver.cpp:130-340``): hunt for 0xFA 0xFB and
discard anything else (ARIA writes ``WMS2\\r`` before SYNC0 on serial links); read
COUNT, then COUNT bytes; drop a frame whose checksum fails. The protocol has no NAK
and no retransmission, so a bad checksum on a serial line is routine: the
:class:`PacketBuffer` reports it as a :class:`CorruptPacket`, counts it and resyncs.
Only the single-frame :func:`decode_packet` raises :class:`ChecksumError`.
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.aria.checksum import aria_checksum
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError

SYNC = b"\xfa\xfb"
"""The two header bytes that start every frame."""
HEADER_LEN = 3
"""SYNC plus the COUNT byte."""
CHECKSUM_LEN = 2
MIN_COUNT = 3
"""Smallest COUNT: an ID byte and the two checksum bytes, no DATA."""
MAX_COUNT = 255
"""COUNT is one unsigned byte; ARIA's receiver accepts up to 255 (manuals say 200/249)."""
MAX_DATA_LEN = MAX_COUNT - MIN_COUNT
"""Most DATA bytes a frame can carry (252)."""
MIN_FRAME_LEN = HEADER_LEN + MIN_COUNT


@dataclass(frozen=True, slots=True)
class Packet:
    """One frame's content: its ID byte and its DATA bytes.

    Attributes:
        packet_id: the ID byte, 0..255 (a command number, a SIP type, 0x20 CONFIG, ...).
        data: the bytes between ID and checksum, at most :data:`MAX_DATA_LEN`.

    Raises:
        LocalProtocolError: on an ID outside 0..255 or DATA too long for one frame.
    """

    packet_id: int
    data: bytes = b""

    def __post_init__(self) -> None:
        if not 0 <= self.packet_id <= 0xFF:
            raise LocalProtocolError(f"packet ID {self.packet_id} is outside 0..255")
        if len(self.data) > MAX_DATA_LEN:
            raise LocalProtocolError(
                f"packet 0x{self.packet_id:02X}: {len(self.data)} data bytes exceed the "
                f"{MAX_DATA_LEN} one frame can carry (COUNT <= {MAX_COUNT})"
            )

    def to_bytes(self) -> bytes:
        """The complete frame: SYNC, COUNT, ID, DATA, checksum (big-endian)."""
        return encode_packet(self.packet_id, self.data)


@dataclass(frozen=True, slots=True)
class CorruptPacket:
    """A frame that failed its checksum; it was counted and skipped.

    Attributes:
        frame: the whole frame as received, SYNC to checksum.
        expected: the checksum computed over its ID and DATA.
        actual: the checksum it carried.
    """

    frame: bytes
    expected: int
    actual: int

    @property
    def packet_id(self) -> int:
        """The ID byte the frame claims (itself possibly corrupt)."""
        return self.frame[HEADER_LEN]


def encode_packet(packet_id: int, data: bytes = b"") -> bytes:
    """Frame ``packet_id`` and ``data``.

    Args:
        packet_id: the ID byte, 0..255.
        data: up to :data:`MAX_DATA_LEN` bytes.

    Returns:
        ``FA FB COUNT ID DATA CKS_HI CKS_LO`` with ``COUNT = len(data) + 3``.

    Raises:
        LocalProtocolError: on an ID outside 0..255 or DATA too long.
    """
    Packet(packet_id, data)  # validates
    body = bytes((packet_id,)) + bytes(data)
    checksum = aria_checksum(body)
    return SYNC + bytes((len(body) + CHECKSUM_LEN,)) + body + checksum.to_bytes(2, "big")


def decode_packet(frame: bytes) -> Packet:
    """Decode exactly one complete frame.

    Args:
        frame: SYNC through checksum, nothing before or after.

    Returns:
        The frame's ID and DATA.

    Raises:
        ChecksumError: the checksum does not match (``expected`` computed, ``actual`` carried).
        RemoteProtocolError: the bytes are not one well-formed frame (message says why).
    """
    frame = bytes(frame)
    if len(frame) < MIN_FRAME_LEN:
        raise RemoteProtocolError(
            f"frame of {len(frame)} bytes is shorter than the minimum {MIN_FRAME_LEN}"
        )
    if frame[:2] != SYNC:
        raise RemoteProtocolError(f"frame starts with {frame[:2].hex(' ').upper()}, not FA FB")
    count = frame[2]
    if count < MIN_COUNT:
        raise RemoteProtocolError(f"COUNT {count} is below the minimum {MIN_COUNT}")
    if len(frame) != HEADER_LEN + count:
        raise RemoteProtocolError(
            f"COUNT {count} says {count} bytes follow it, but {len(frame) - HEADER_LEN} do"
        )
    body = frame[HEADER_LEN:-CHECKSUM_LEN]
    expected = aria_checksum(body)
    actual = int.from_bytes(frame[-CHECKSUM_LEN:], "big")
    if expected != actual:
        raise ChecksumError(expected, actual)
    return Packet(body[0], body[1:])


class PacketBuffer:
    """Streaming deframer: arbitrary chunks in, packets (or corrupt frames) out.

    Rules:

    1. Bytes before a SYNC are garbage: skipped and counted (``WMS2\\r`` on serial).
    2. A frame that is not complete yet stays buffered until more bytes arrive.
    3. A frame with a bad checksum is returned as a :class:`CorruptPacket` and counted;
       scanning resumes at the byte after its 0xFA, not after the whole frame, so a
       dropped or corrupted COUNT byte cannot swallow the frames that follow. A
       corrupt frame whose DATA happens to contain FA FB may therefore count twice:
       ``bad_checksums`` counts failed checks, not lost packets.
    4. A COUNT below 3 cannot start a frame: its 0xFA is skipped.
    5. :meth:`abandon_partial` gives up on a partial frame that stopped growing (ARIA
       waits 100 ms); the caller owns the time, so it decides when.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self._start = 0
        self.bad_checksums = 0
        """Frames that failed their checksum."""
        self.skipped_bytes = 0
        """Bytes discarded while hunting for SYNC (garbage, and bytes of failed frames)."""
        self.abandoned_frames = 0
        """Partial frames given up by :meth:`abandon_partial`."""

    @property
    def pending_bytes(self) -> int:
        """Buffered bytes not yet returned as a packet or skipped."""
        return len(self._buf) - self._start

    def feed(self, data: bytes) -> None:
        """Append received bytes (any chunking)."""
        self._buf += data

    def next_frame(self) -> Packet | CorruptPacket | None:
        """The next complete frame, or ``None`` until more bytes arrive."""
        buf = self._buf
        while True:
            at = buf.find(SYNC, self._start)
            if at < 0:
                # Keep a trailing 0xFA: it may be the first half of a SYNC.
                keep = 1 if self.pending_bytes and buf[-1] == SYNC[0] else 0
                self._skip(self.pending_bytes - keep)
                self._compact()
                return None
            self._skip(at - self._start)
            if len(buf) < at + HEADER_LEN:
                return None
            count = buf[at + 2]
            if count < MIN_COUNT:
                self._skip(1)
                continue
            end = at + HEADER_LEN + count
            if len(buf) < end:
                return None
            body = bytes(buf[at + HEADER_LEN : end - CHECKSUM_LEN])
            expected = aria_checksum(body)
            actual = buf[end - 2] << 8 | buf[end - 1]
            if expected != actual:
                self.bad_checksums += 1
                corrupt = CorruptPacket(bytes(buf[at:end]), expected, actual)
                self._skip(1)
                return corrupt
            self._start = end
            self._compact()
            return Packet(body[0], body[1:])

    def abandon_partial(self) -> None:
        """Give up on the partial frame at the front of the buffer.

        Call only after :meth:`next_frame` returned ``None`` with bytes pending. Drops
        the frame's first byte, so the next scan looks for a SYNC after it.
        """
        if self.pending_bytes:
            self.abandoned_frames += 1
            self._skip(1)

    def _skip(self, n: int) -> None:
        self._start += n
        self.skipped_bytes += n

    def _compact(self) -> None:
        if self._start:
            del self._buf[: self._start]
            self._start = 0
