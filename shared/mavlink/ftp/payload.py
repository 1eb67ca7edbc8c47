"""MAVLink FTP's payload (FILE_TRANSFER_PROTOCOL, id 110): the codec both ends share.

Both cores speak the message's 251-byte ``payload``; the adapter packs it into
FILE_TRANSFER_PROTOCOL (a reply goes to the requester's system and component) and
hands received payloads in.

Payload (little-endian; ``data`` is padded with zeros to 239 bytes)::

    seq:u16 | session:u8 | opcode:u8 | size:u8 | req_opcode:u8 | burst_complete:u8
    | padding:u8 | offset:u32 | data[239]
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

from shared.errors import LocalProtocolError, RemoteProtocolError

#: Bytes in the FILE_TRANSFER_PROTOCOL payload field.
PAYLOAD_LEN = 251
#: Header bytes before ``data``.
HEADER_LEN = 12
#: Largest ``data``, bytes.
MAX_DATA = PAYLOAD_LEN - HEADER_LEN
_HEADER = struct.Struct("<HBBBBBxI")
#: A u32 in ACK data: a file size (OpenFileRO reply) or a CRC32 (CalcFileCRC32 reply).
U32 = struct.Struct("<I")


class Opcode(IntEnum):
    """FTP opcodes (pymavlink ``mavftp_op.py``); sizes and offsets in bytes."""

    NONE = 0  #: ignored, always ACKed
    TERMINATE_SESSION = 1  #: closes ``session`` (commits an upload)
    RESET_SESSIONS = 2  #: closes every session
    LIST_DIRECTORY = 3  #: data = path, offset = index of the first entry wanted
    OPEN_FILE_RO = 4  #: data = path; ACK data = u32 file size
    READ_FILE = 5  #: session, offset, size = bytes wanted
    CREATE_FILE = 6  #: data = path; NAK FileExists if it exists
    WRITE_FILE = 7  #: session, offset, data
    REMOVE_FILE = 8  #: data = path
    CREATE_DIRECTORY = 9  #: unsupported here
    REMOVE_DIRECTORY = 10  #: unsupported here
    OPEN_FILE_WO = 11  #: data = path; the upload replaces the file
    TRUNCATE_FILE = 12  #: unsupported here
    RENAME = 13  #: unsupported here
    CALC_FILE_CRC32 = 14  #: data = path; ACK data = u32 :func:`crc32_mavlink`
    BURST_READ_FILE = 15  #: session, offset, size = bytes per reply packet
    ACK = 128  #: reply: success
    NAK = 129  #: reply: data[0] = NakCode, FAIL_ERRNO adds data[1] = errno


class NakCode(IntEnum):
    """``data[0]`` of a NAK."""

    FAIL = 1  #: unspecified failure
    FAIL_ERRNO = 2  #: data[1] = the server's errno
    INVALID_DATA_SIZE = 3  #: size or data out of range
    INVALID_SESSION = 4  #: no such session (or the wrong kind)
    NO_SESSIONS_AVAILABLE = 5  #: all sessions in use; MAVProxy waits and retries
    EOF = 6  #: offset at or past the end (also ends a listing)
    UNKNOWN_COMMAND = 7  #: opcode not supported
    FILE_EXISTS = 8  #: CreateFile on an existing file
    FILE_PROTECTED = 9  #: not allowed there (read-only, outside the upload area)
    FILE_NOT_FOUND = 10  #: no such file or directory


def crc32_mavlink(data: bytes, crc: int = 0) -> int:
    """MAVLink's CRC32 (FTP CalcFileCRC32; devguide ``guide/crc.md``).

    Gary Brown's reflected CRC-32 (polynomial 0x04C11DB7, table 0xEDB88320) as in
    zlib, but starting at 0 instead of 0xFFFFFFFF and without the final XOR; i.e.
    CRC-32/JAMCRC with initial value 0. zlib inverts on entry and exit, so the
    register is passed in and taken out inverted.

    Args:
        data: the bytes to add.
        crc: the CRC of the bytes before ``data`` (chain calls), 0 to start.
    """
    return zlib.crc32(data, crc ^ 0xFFFFFFFF) ^ 0xFFFFFFFF


@dataclass(frozen=True, slots=True)
class FtpPayload:
    """One FTP payload: a request or a reply.

    ``size`` is ``len(data)`` except in ReadFile/BurstReadFile requests, where it
    is the number of bytes wanted and ``data`` is empty.
    """

    seq: int
    session: int
    opcode: int
    size: int = 0
    req_opcode: int = 0
    burst_complete: bool = False
    offset: int = 0
    data: bytes = b""

    def __post_init__(self) -> None:
        for name, limit in (("seq", 0xFFFF), ("session", 0xFF), ("opcode", 0xFF),
                            ("size", 0xFF), ("req_opcode", 0xFF), ("offset", 0xFFFFFFFF)):
            value = getattr(self, name)
            if not 0 <= value <= limit:
                raise LocalProtocolError(f"FTP {name} {value} outside 0..{limit}")
        if len(self.data) > MAX_DATA:
            raise LocalProtocolError(f"FTP data of {len(self.data)} bytes (max {MAX_DATA})")

    def to_bytes(self) -> bytes:
        """The 251-byte payload field."""
        header = _HEADER.pack(self.seq, self.session, self.opcode, self.size,
                              self.req_opcode, int(self.burst_complete), self.offset)
        return (header + self.data).ljust(PAYLOAD_LEN, b"\0")

    @classmethod
    def from_bytes(cls, payload: bytes | Sequence[int]) -> FtpPayload:
        """Decode a payload field (pymavlink gives a list of 251 ints).

        Raises:
            RemoteProtocolError: shorter than the 12-byte header.
        """
        raw = bytes(payload)
        if len(raw) < HEADER_LEN:
            raise RemoteProtocolError(f"FTP payload of {len(raw)} bytes (header is {HEADER_LEN})")
        seq, session, opcode, size, req_opcode, burst, offset = _HEADER.unpack_from(raw)
        data = raw[HEADER_LEN:HEADER_LEN + min(size, MAX_DATA)]
        return cls(seq, session, opcode, size, req_opcode, bool(burst), offset, data)


@dataclass(frozen=True, slots=True)
class DirEntry:
    """One ListDirectory entry: ``"F<name>\\t<size>\\0"`` or ``"D<name>\\0"``."""

    name: str
    is_dir: bool
    size: int = 0
    """File length, bytes; 0 for a directory."""

    def to_bytes(self) -> bytes:
        name = self.name.encode("utf-8")
        return b"D" + name + b"\0" if self.is_dir else b"F%s\t%d\0" % (name, self.size)

    @classmethod
    def from_bytes(cls, entry: bytes) -> DirEntry | None:
        """Parse one entry (without its NUL); None for ``S`` (skip) and unknown kinds."""
        text = entry.decode("utf-8", errors="replace")
        if text.startswith("D"):
            return cls(text[1:], True)
        name, tab, size = text[1:].rpartition("\t")
        if text.startswith("F") and tab and size.isdigit():
            return cls(name, False, int(size))
        return None
