"""The ARIA packet checksum (reference §1; ``ArRobotPacket.cpp:120 calcCheckSum``)."""

from __future__ import annotations

import struct


def aria_checksum(body: bytes) -> int:
    """Checksum of a packet body (ID + DATA), as the 16-bit value sent high byte first.

    Algorithm: sum the body as successive big-endian 16-bit words
    ``(b[i] << 8) | b[i+1]``, keeping 16 bits after each addition; if the body has
    an odd length, XOR its last byte into the low byte of the sum. This is ARIA's
    ``calcCheckSum`` and the P2 manual's ``calc_chksum``. Note that the words are
    big-endian although every integer *field* of the protocol is little-endian.

    Args:
        body: the packet's ID byte followed by its DATA bytes (no header, COUNT or
            checksum).

    Returns:
        The checksum, 0..0xFFFF; transmit as ``(value >> 8, value & 0xFF)``.

    Example:
        ENABLE 1 has body ``04 3B 01 00``: 0x043B + 0x0100 = 0x053B.
    """
    pairs = len(body) // 2
    # Masking once at the end equals masking after each addition (sum mod 2**16).
    words: tuple[int, ...] = struct.unpack_from(f">{pairs}H", body)
    total = sum(words) & 0xFFFF
    if len(body) % 2:
        total ^= body[-1]
    return total
