"""MAVLink FTP (FILE_TRANSFER_PROTOCOL, id 110), sans-I/O: payload codec, server, client.

Both cores speak the message's 251-byte ``payload``; the adapter packs it into
FILE_TRANSFER_PROTOCOL (a reply goes to the requester's system and component) and
hands received payloads in. References: mavlink-vehicle.md §0.5-0.8 and §1.6,
mavlink.io/en/services/ftp.html, pymavlink ``mavftp.py``.

Payload (little-endian; ``data`` is padded with zeros to 239 bytes)::

    seq:u16 | session:u8 | opcode:u8 | size:u8 | req_opcode:u8 | burst_complete:u8
    | padding:u8 | offset:u32 | data[239]

Server rules:

1. A reply has ``seq`` = request seq + 1 (the packets of a burst count on: +1, +2,
   ...), ``req_opcode`` = the request's opcode, and **the request's session byte**,
   also on OpenFileRO/CreateFile/OpenFileWO: MAVProxy picks the session byte and
   drops replies carrying another one (§0.6).
2. A request byte-identical to the previous one from the same peer is a retry after
   a lost reply: the cached replies go out again and nothing runs twice (a retried
   CreateFile must not fail with FileExists). NoSessionsAvailable is not cached:
   the client is meant to retry until a session frees.
3. Policy lives in the :class:`FtpFileSystem`. Its ``OSError``\\ s become NAKs:
   FileNotFoundError/NotADirectoryError -> FileNotFound, PermissionError/EROFS ->
   FileProtected, FileExistsError -> FileExists, another errno -> FailErrno.
4. ArduPilot's virtual files (``@PARAM/param.pck``, ``@MISSION/...``, ``@SYS/...``)
   get FileNotFound at once, so MAVProxy falls back to PARAM_REQUEST_LIST (§0.8).
5. At most ``max_sessions`` sessions are open; one unused for ``session_timeout_ns``
   is closed (an upload discarded) when the next request arrives. TerminateSession
   commits an upload; ResetSessions discards every upload in progress.

Client rules:

1. One operation at a time, each with the next session byte. Replies with another
   session byte (except to an open) or matching no request in flight are ignored.
2. A request is resent unchanged (same seq) after ``ack_timeout_ns`` without a
   reply, or after NoSessionsAvailable, up to ``retries`` times; then the operation
   fails.
3. A download learns the file size from OpenFileRO, burst-reads from the high-water
   mark (a burst silent for ``ack_timeout_ns`` restarts there; ``retries`` stalls in
   a row fail), then reads the bytes still missing with up to ``max_in_flight``
   ReadFiles, so a lost burst packet costs only its own bytes.
4. An upload pipelines up to ``max_in_flight`` WriteFiles and ends with
   TerminateSession, whose ACK means committed. After a failure nothing more is
   sent: the server drops the unfinished upload after ``session_timeout_ns``.
"""

from __future__ import annotations

import errno
import itertools
import struct
import zlib
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Protocol

from shared.config import FtpConfig
from shared.errors import LocalProtocolError, RemoteProtocolError

#: Bytes in the FILE_TRANSFER_PROTOCOL payload field.
PAYLOAD_LEN = 251
#: Header bytes before ``data``.
HEADER_LEN = 12
#: Largest ``data``, bytes.
MAX_DATA = PAYLOAD_LEN - HEADER_LEN
_HEADER = struct.Struct("<HBBBBBxI")
_U32 = struct.Struct("<I")


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


def _request(seq: int, session: int, opcode: Opcode, data: bytes = b"", offset: int = 0,
             size: int | None = None) -> FtpPayload:
    return FtpPayload(seq, session, opcode, len(data) if size is None else size,
                      offset=offset, data=data)


def _reply(request: FtpPayload, data: bytes = b"", nth: int = 0, burst_complete: bool = False,
           offset: int | None = None, opcode: Opcode = Opcode.ACK) -> FtpPayload:
    """A reply to ``request``: rule 1 (``nth`` counts the packets of a burst)."""
    return FtpPayload((request.seq + 1 + nth) & 0xFFFF, request.session, opcode, len(data),
                      request.opcode, burst_complete,
                      request.offset if offset is None else offset, data)


def _nak(request: FtpPayload, code: NakCode, errno_value: int = 0) -> FtpPayload:
    data = bytes([code, errno_value & 0xFF]) if code is NakCode.FAIL_ERRNO else bytes([code])
    return _reply(request, data, opcode=Opcode.NAK)


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


# -- server ----------------------------------------------------------------------


class FtpReader(Protocol):
    """A file opened for reading; a consistent view while open."""

    @property
    def size(self) -> int:
        """File length, bytes."""
        ...

    def read(self, offset: int, size: int) -> bytes:
        """Up to ``size`` bytes from byte ``offset`` (fewer at the end)."""
        ...

    def close(self) -> None: ...


class FtpWriter(Protocol):
    """An upload in progress: invisible until :meth:`commit`."""

    def write(self, offset: int, data: bytes) -> None:
        """Store ``data`` at byte ``offset`` (writes may come in any order)."""
        ...

    def commit(self) -> None:
        """Make the file visible atomically; raises OSError (and discards) if incomplete."""
        ...

    def discard(self) -> None: ...


class FtpFileSystem(Protocol):
    """What the server serves. Refusals are ``OSError``\\ s (server rule 3)."""

    def list_directory(self, path: str) -> Sequence[DirEntry]: ...

    def open_read(self, path: str) -> FtpReader: ...

    def open_write(self, path: str, exclusive: bool) -> FtpWriter:
        """Start an upload; ``exclusive`` (CreateFile) refuses an existing file."""
        ...

    def remove(self, path: str) -> None: ...


class _NakError(Exception):
    """Inside the server: answer the request with this NAK."""

    def __init__(self, code: NakCode) -> None:
        self.code = code


@dataclass(slots=True)
class _Session:
    last_used_ns: int
    reader: FtpReader | None = None
    writer: FtpWriter | None = None

    def close(self, commit: bool) -> None:
        if self.reader is not None:
            self.reader.close()
        elif self.writer is not None and commit:
            self.writer.commit()
        elif self.writer is not None:
            self.writer.discard()


def _nak_for(request: FtpPayload, e: OSError) -> FtpPayload:
    """Server rule 3."""
    if isinstance(e, FileNotFoundError | NotADirectoryError):
        return _nak(request, NakCode.FILE_NOT_FOUND)
    if isinstance(e, PermissionError) or e.errno == errno.EROFS:
        return _nak(request, NakCode.FILE_PROTECTED)
    if isinstance(e, FileExistsError):
        return _nak(request, NakCode.FILE_EXISTS)
    if e.errno:
        return _nak(request, NakCode.FAIL_ERRNO, e.errno)
    return _nak(request, NakCode.FAIL)


def _path(request: FtpPayload) -> str:
    """The path in a request's data (up to the first NUL); rule 4 for ``@`` paths."""
    if request.size > MAX_DATA:
        raise _NakError(NakCode.INVALID_DATA_SIZE)
    try:
        path = request.data.split(b"\0", 1)[0].decode("utf-8")
    except UnicodeDecodeError:
        raise FileNotFoundError(errno.ENOENT, "path is not UTF-8") from None
    if path.startswith("@"):
        raise FileNotFoundError(errno.ENOENT, "no virtual files", path)
    return path


#: A server operation: (request, now_ns) -> replies; raises _NakError or OSError.
_Handler = Callable[[FtpPayload, int], list[FtpPayload]]


class FtpServer:
    """The vehicle's FTP server over a :class:`FtpFileSystem` (module rules 1-5).

    Args:
        fs: what to serve.
        config: session limits and burst length.
    """

    def __init__(self, fs: FtpFileSystem, config: FtpConfig | None = None) -> None:
        self.fs = fs
        self.config = config if config is not None else FtpConfig()
        self._sessions: dict[int, _Session] = {}
        self._last: dict[Hashable, tuple[bytes, list[bytes]]] = {}
        self._handlers: dict[int, _Handler] = {
            Opcode.NONE: lambda r, _: [_reply(r)],
            Opcode.TERMINATE_SESSION: self._terminate,
            Opcode.RESET_SESSIONS: self._reset,
            Opcode.LIST_DIRECTORY: self._list,
            Opcode.OPEN_FILE_RO: self._open_ro,
            Opcode.READ_FILE: self._read,
            Opcode.BURST_READ_FILE: self._burst,
            Opcode.CREATE_FILE: lambda r, now: self._open_wo(r, now, exclusive=True),
            Opcode.OPEN_FILE_WO: lambda r, now: self._open_wo(r, now, exclusive=False),
            Opcode.WRITE_FILE: self._write,
            Opcode.REMOVE_FILE: self._remove,
            Opcode.CALC_FILE_CRC32: self._crc,
        }

    @property
    def open_sessions(self) -> int:
        """Sessions open now."""
        return len(self._sessions)

    def handle(self, payload: bytes | Sequence[int], now_ns: int,
               peer: Hashable = None) -> list[bytes]:
        """Answer one request.

        Args:
            payload: the request's payload field.
            now_ns: when it arrived, ns (session time-outs).
            peer: who sent it, e.g. ``(sysid, compid)``; keys the retry cache (rule 2).

        Returns:
            Reply payload fields (251 bytes each) in sending order; several for a
            burst read, none for a payload too short to parse.
        """
        raw = bytes(payload)
        cached = self._last.get(peer)
        if cached is not None and cached[0] == raw:
            return list(cached[1])
        try:
            request = FtpPayload.from_bytes(raw)
        except RemoteProtocolError:
            return []
        self._expire(now_ns)
        handler = self._handlers.get(request.opcode)
        try:
            if handler is None:
                raise _NakError(NakCode.UNKNOWN_COMMAND)
            replies = handler(request, now_ns)
        except _NakError as e:
            replies = [_nak(request, e.code)]
        except OSError as e:
            replies = [_nak_for(request, e)]
        out = [reply.to_bytes() for reply in replies]
        if replies[0].data != bytes([NakCode.NO_SESSIONS_AVAILABLE]):  # a retry may succeed
            self._last[peer] = (raw, out)
        return out

    def _expire(self, now_ns: int) -> None:
        for session_id, session in list(self._sessions.items()):
            if now_ns - session.last_used_ns >= self.config.session_timeout_ns:
                del self._sessions[session_id]
                session.close(commit=False)

    def _session(self, request: FtpPayload, now_ns: int) -> _Session:
        session = self._sessions.get(request.session)
        if session is None:
            raise _NakError(NakCode.INVALID_SESSION)
        session.last_used_ns = now_ns
        return session

    def _add_session(self, request: FtpPayload, session: _Session) -> None:
        """Give ``session`` the request's id (rule 1), replacing a stale one."""
        old = self._sessions.pop(request.session, None)
        if old is not None:
            old.close(commit=False)
        if len(self._sessions) >= self.config.max_sessions:
            session.close(commit=False)
            raise _NakError(NakCode.NO_SESSIONS_AVAILABLE)
        self._sessions[request.session] = session

    def _terminate(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        self._session(request, now_ns)
        self._sessions.pop(request.session).close(commit=True)
        return [_reply(request)]

    def close(self) -> None:
        """Close every session, discarding uploads in progress (ResetSessions; shutdown)."""
        sessions, self._sessions = self._sessions, {}
        for session in sessions.values():
            session.close(commit=False)

    def _reset(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        self.close()
        return [_reply(request)]

    def _list(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        # Entries longer than a packet are left out before indexing, so that the
        # offset (an entry index) means the same in every reply.
        entries = [e.to_bytes() for e in self.fs.list_directory(_path(request))]
        entries = [e for e in entries if len(e) <= MAX_DATA]
        if request.offset >= len(entries):
            raise _NakError(NakCode.EOF)
        data = b""
        for entry in entries[request.offset:]:
            if len(data) + len(entry) > MAX_DATA:
                break
            data += entry
        return [_reply(request, data)]

    def _open_ro(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        reader = self.fs.open_read(_path(request))
        self._add_session(request, _Session(now_ns, reader=reader))
        return [_reply(request, _U32.pack(reader.size))]

    def _open_wo(self, request: FtpPayload, now_ns: int, exclusive: bool) -> list[FtpPayload]:
        writer = self.fs.open_write(_path(request), exclusive)
        self._add_session(request, _Session(now_ns, writer=writer))
        return [_reply(request)]

    def _reader(self, request: FtpPayload, now_ns: int) -> FtpReader:
        reader = self._session(request, now_ns).reader
        if reader is None:
            raise _NakError(NakCode.INVALID_SESSION)
        if request.offset >= reader.size:
            raise _NakError(NakCode.EOF)
        return reader

    def _read(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        reader = self._reader(request, now_ns)
        return [_reply(request, reader.read(request.offset, _chunk(request)))]

    def _burst(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        reader = self._reader(request, now_ns)
        replies, offset, chunk = [], request.offset, _chunk(request)
        for nth in range(self.config.burst_packets):
            data = reader.read(offset, chunk)
            last = offset + len(data) >= reader.size or nth == self.config.burst_packets - 1
            replies.append(_reply(request, data, nth, burst_complete=last, offset=offset))
            offset += len(data)
            if last:
                break
        return replies

    def _write(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        writer = self._session(request, now_ns).writer
        if writer is None:
            raise _NakError(NakCode.INVALID_SESSION)
        if request.size > MAX_DATA:
            raise _NakError(NakCode.INVALID_DATA_SIZE)
        writer.write(request.offset, request.data)
        return [_reply(request)]

    def _remove(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        self.fs.remove(_path(request))
        return [_reply(request)]

    def _crc(self, request: FtpPayload, now_ns: int) -> list[FtpPayload]:
        reader, crc, offset = self.fs.open_read(_path(request)), 0, 0
        try:
            while offset < reader.size:
                block = reader.read(offset, 1 << 16)
                if not block:
                    break
                crc, offset = crc32_mavlink(block, crc), offset + len(block)
        finally:
            reader.close()
        return [_reply(request, _U32.pack(crc))]


def _chunk(request: FtpPayload) -> int:
    """Bytes per read reply: the size asked for, at most a packet (0 means a packet)."""
    return request.size if 0 < request.size <= MAX_DATA else MAX_DATA


# -- client ------------------------------------------------------------------------


def _nak_code(reply: FtpPayload) -> NakCode | None:
    """None for an ACK, else the NAK's code (FAIL when missing or unknown)."""
    if reply.opcode != Opcode.NAK:
        return None
    try:
        return NakCode(reply.data[0])
    except (IndexError, ValueError):
        return NakCode.FAIL


@dataclass(frozen=True, slots=True)
class Listed:
    """A directory listing finished."""

    path: str
    entries: tuple[DirEntry, ...]


@dataclass(frozen=True, slots=True)
class Downloaded:
    """A file was read completely."""

    path: str
    data: bytes


@dataclass(frozen=True, slots=True)
class Uploaded:
    """A file was written and its session closed (the server committed it)."""

    path: str
    size: int
    """Bytes written."""


@dataclass(frozen=True, slots=True)
class Checksummed:
    """The server computed a file's :func:`crc32_mavlink`."""

    path: str
    crc32: int


@dataclass(frozen=True, slots=True)
class FtpFailed:
    """An operation gave up: a NAK (``nak`` set) or no reply after the retries."""

    path: str
    operation: str
    reason: str
    nak: NakCode | None = None


FtpEvent = Listed | Downloaded | Uploaded | Checksummed | FtpFailed


@dataclass(slots=True)
class _Pending:
    """A request waiting for its reply."""

    request: FtpPayload
    deadline_ns: int
    sends: int = 1


@dataclass(slots=True)
class _Operation:
    kind: Opcode  # the first request: LIST_DIRECTORY, OPEN_FILE_RO, CREATE_FILE, CALC_FILE_CRC32
    path: str
    upload: bytes = b""
    entries: list[DirEntry] = field(default_factory=list)
    data: bytearray = field(default_factory=bytearray)
    missing: list[tuple[int, int]] = field(default_factory=list)  # [start, end) byte ranges
    unsent: list[int] = field(default_factory=list)  # write offsets not yet sent, descending
    bursting: bool = False
    burst_end: int = 0  # end of the last burst packet received, bytes
    closing: bool = False  # TerminateSession sent


class FtpClient:
    """The ground station's FTP client (module docstring, client rules).

    Usage::

        client.get("/memory/manifest.json", clock.now_ns())
        while (event := client.next_event()) is None:
            for payload in client.payloads_to_send():
                link.send(payload)                  # FILE_TRANSFER_PROTOCOL to the robot
            ...                                      # wait for a reply or get_timer()
            client.receive_payload(reply, clock.now_ns())   # or handle_timer(now_ns)

    Args:
        config: timeouts, retries and packet sizes.
        session: the session byte of the first operation; each operation uses the next.
    """

    def __init__(self, config: FtpConfig | None = None, session: int = 0) -> None:
        self.config = config if config is not None else FtpConfig()
        self._session = (session - 1) & 0xFF
        self._seq = 0
        self._op: _Operation | None = None
        self._pending: dict[int, _Pending] = {}  # by the seq of the expected reply
        self._burst: _Pending | None = None
        self._outbox: list[bytes] = []
        self._events: list[FtpEvent] = []

    @property
    def busy(self) -> bool:
        """An operation is in progress."""
        return self._op is not None

    # -- starting operations ---------------------------------------------------------

    def list_directory(self, path: str, now_ns: int) -> None:
        """List ``path``; ends with :class:`Listed` or :class:`FtpFailed`."""
        self._start(Opcode.LIST_DIRECTORY, path, now_ns)

    def get(self, path: str, now_ns: int) -> None:
        """Download ``path``; ends with :class:`Downloaded` or :class:`FtpFailed`."""
        self._start(Opcode.OPEN_FILE_RO, path, now_ns)

    def put(self, path: str, data: bytes, now_ns: int) -> None:
        """Upload ``data`` as the new file ``path``; ends with :class:`Uploaded` or
        :class:`FtpFailed`."""
        self._start(Opcode.CREATE_FILE, path, now_ns, bytes(data))

    def crc32(self, path: str, now_ns: int) -> None:
        """Ask for ``path``'s CRC; ends with :class:`Checksummed` or :class:`FtpFailed`."""
        self._start(Opcode.CALC_FILE_CRC32, path, now_ns)

    def _start(self, kind: Opcode, path: str, now_ns: int, upload: bytes = b"") -> None:
        if self._op is not None:
            raise LocalProtocolError(f"FTP {self._op.kind.name} of {self._op.path} in progress")
        encoded = path.encode("utf-8")
        if len(encoded) > MAX_DATA:
            raise LocalProtocolError(f"FTP path of {len(encoded)} bytes (max {MAX_DATA}): {path}")
        self._session = (self._session + 1) & 0xFF
        self._op = _Operation(kind, path, upload)
        self._send(kind, now_ns, encoded)

    # -- I/O surface -------------------------------------------------------------

    def payloads_to_send(self) -> list[bytes]:
        """Payload fields (251 bytes) to send now, in order; empties the queue."""
        out, self._outbox = self._outbox, []
        return out

    def next_event(self) -> FtpEvent | None:
        """The next finished operation, or None."""
        return self._events.pop(0) if self._events else None

    def get_timer(self) -> int | None:
        """The earliest resend deadline, ns; None when nothing is outstanding."""
        deadlines = [p.deadline_ns for p in self._pending.values()]
        if self._burst is not None:
            deadlines.append(self._burst.deadline_ns)
        return min(deadlines) if deadlines else None

    def handle_timer(self, now_ns: int) -> None:
        """Resend what is overdue, or fail the operation when its retries are spent."""
        op = self._op
        for pending in [p for p in self._pending.values() if p.deadline_ns <= now_ns]:
            if pending.sends > self.config.retries:
                return self._fail(f"no reply to {Opcode(pending.request.opcode).name} "
                                  f"after {pending.sends} tries")
            self._resend(pending, now_ns)
        burst = self._burst
        if op is not None and burst is not None and burst.deadline_ns <= now_ns:
            if burst.sends > self.config.retries:
                return self._fail(f"burst read stalled {burst.sends} times")
            self._burst = None  # a stalled burst restarts from the high-water mark
            self._read_more(op, now_ns)
            if self._burst is not None:
                self._burst.sends = burst.sends + 1

    def receive_payload(self, payload: bytes | Sequence[int], now_ns: int) -> None:
        """Feed one received FILE_TRANSFER_PROTOCOL payload field."""
        try:
            reply = FtpPayload.from_bytes(payload)
        except RemoteProtocolError:
            return
        op = self._op
        if op is None or reply.opcode not in (Opcode.ACK, Opcode.NAK):
            return
        if reply.req_opcode == Opcode.BURST_READ_FILE:
            if self._burst is not None and reply.session == self._session:
                self._on_burst(op, reply, now_ns)
            return
        key = reply.seq
        pending = self._pending.get(key)
        if pending is None or pending.request.opcode != reply.req_opcode:
            return
        # Servers that allocate their own session ids answer an open with another one.
        opened = reply.req_opcode in (Opcode.OPEN_FILE_RO, Opcode.CREATE_FILE)
        if reply.session != self._session and not opened:
            return
        if _nak_code(reply) is NakCode.NO_SESSIONS_AVAILABLE:
            return  # resent when its timer runs out, like a lost reply
        del self._pending[key]
        self._session = reply.session
        self._on_reply(op, pending.request, reply, _nak_code(reply), now_ns)

    # -- the operations ------------------------------------------------------------

    def _on_reply(self, op: _Operation, request: FtpPayload, reply: FtpPayload,
                  nak: NakCode | None, now_ns: int) -> None:
        kind = Opcode(request.opcode)
        if kind is Opcode.TERMINATE_SESSION:
            if nak is not None and op.kind is Opcode.CREATE_FILE:
                return self._fail("the server did not commit the upload", nak)
            return self._finish(op)
        if kind is Opcode.LIST_DIRECTORY:
            if nak is NakCode.EOF:
                return self._finish(op)
            if nak is None:
                chunks = [c for c in reply.data.split(b"\0") if c]
                op.entries += [e for c in chunks if (e := DirEntry.from_bytes(c)) is not None]
                self._send(kind, now_ns, request.data, request.offset + len(chunks))
                return None
        elif nak is None and kind is Opcode.CALC_FILE_CRC32 and len(reply.data) >= 4:
            op.data[:] = reply.data[:4]
            return self._finish(op)
        elif nak is None and kind is Opcode.OPEN_FILE_RO and len(reply.data) >= 4:
            size = _U32.unpack_from(reply.data)[0]
            op.data = bytearray(size)
            op.missing = [(0, size)] if size else []
            op.bursting = size > 0
            return self._read_more(op, now_ns)
        elif kind is Opcode.READ_FILE and nak is None:
            self._store(op, reply)
            return self._read_more(op, now_ns)
        elif kind is Opcode.CREATE_FILE and nak is None:
            size = self.config.write_size_bytes
            op.unsent = list(range(0, len(op.upload), size))[::-1]
            return self._write_more(op, now_ns)
        elif kind is Opcode.WRITE_FILE and nak is None:
            return self._write_more(op, now_ns)
        self._fail(f"{kind.name} refused" if nak else f"bad {kind.name} reply", nak)

    def _on_burst(self, op: _Operation, reply: FtpPayload, now_ns: int) -> None:
        assert self._burst is not None
        nak = _nak_code(reply)
        if nak is not None and nak is not NakCode.EOF:
            return self._fail("BURST_READ_FILE refused", nak)
        if nak is NakCode.EOF:
            op.bursting = False
        else:
            self._store(op, reply)
            op.burst_end = max(op.burst_end, reply.offset + len(reply.data))
            self._burst.deadline_ns = now_ns + self.config.ack_timeout_ns
            if not reply.burst_complete:
                return
            op.bursting = op.burst_end < len(op.data)
        self._burst = None
        self._read_more(op, now_ns)

    def _store(self, op: _Operation, reply: FtpPayload) -> None:
        """Keep a read reply's bytes and strike them from the missing ranges."""
        start, end = reply.offset, min(reply.offset + len(reply.data), len(op.data))
        if start >= end:
            return
        op.data[start:end] = reply.data[:end - start]
        op.missing = [(a, b) for lo, hi in op.missing
                      for a, b in ((lo, min(hi, start)), (max(lo, end), hi)) if a < b]

    def _read_more(self, op: _Operation, now_ns: int) -> None:
        """Burst from the high-water mark, else fill the missing ranges; close when whole."""
        size = self.config.burst_size_bytes
        if not op.missing:
            self._close(op, now_ns)
        elif op.bursting and self._burst is None:
            self._burst = self._send(Opcode.BURST_READ_FILE, now_ns, offset=op.burst_end,
                                     size=size, track=False)
        elif not op.bursting:
            wanted = {p.request.offset for p in self._pending.values()}
            reads = ((offset, min(size, end - offset)) for start, end in op.missing
                     for offset in range(start, end, size) if offset not in wanted)
            room = max(0, self.config.max_in_flight - len(self._pending))
            for offset, length in itertools.islice(reads, room):
                self._send(Opcode.READ_FILE, now_ns, offset=offset, size=length)

    def _write_more(self, op: _Operation, now_ns: int) -> None:
        while op.unsent and len(self._pending) < self.config.max_in_flight:
            offset = op.unsent.pop()
            self._send(Opcode.WRITE_FILE, now_ns,
                       op.upload[offset:offset + self.config.write_size_bytes], offset)
        if not op.unsent and not self._pending:
            self._close(op, now_ns)

    def _close(self, op: _Operation, now_ns: int) -> None:
        if not op.closing:
            op.closing = True
            self._send(Opcode.TERMINATE_SESSION, now_ns)

    def _finish(self, op: _Operation) -> None:
        events: dict[Opcode, Callable[[], FtpEvent]] = {
            Opcode.LIST_DIRECTORY: lambda: Listed(op.path, tuple(op.entries)),
            Opcode.OPEN_FILE_RO: lambda: Downloaded(op.path, bytes(op.data)),
            Opcode.CREATE_FILE: lambda: Uploaded(op.path, len(op.upload)),
            Opcode.CALC_FILE_CRC32: lambda: Checksummed(op.path, _U32.unpack(op.data)[0]),
        }
        self._events.append(events[op.kind]())
        self._end()

    def _fail(self, reason: str, nak: NakCode | None = None) -> None:
        assert self._op is not None
        self._events.append(FtpFailed(self._op.path, self._op.kind.name, reason, nak))
        self._end()

    def _end(self) -> None:
        self._op, self._burst = None, None
        self._pending.clear()

    def _send(self, opcode: Opcode, now_ns: int, data: bytes = b"", offset: int = 0,
              size: int | None = None, track: bool = True) -> _Pending:
        request = _request(self._seq, self._session, opcode, data, offset, size)
        self._seq = (self._seq + 1) & 0xFFFF
        pending = _Pending(request, now_ns + self.config.ack_timeout_ns)
        if track:
            self._pending[(request.seq + 1) & 0xFFFF] = pending
        self._outbox.append(request.to_bytes())
        return pending

    def _resend(self, pending: _Pending, now_ns: int) -> None:
        pending.sends += 1
        pending.deadline_ns = now_ns + self.config.ack_timeout_ns
        self._outbox.append(pending.request.to_bytes())
