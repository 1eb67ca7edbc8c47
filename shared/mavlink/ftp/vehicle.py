"""MAVLink FTP, vehicle side: the server, sans-I/O (payload codec: ``payload.py``).

Rules:

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
"""

from __future__ import annotations

import errno
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass
from typing import Protocol

from shared.config import FtpConfig
from shared.errors import RemoteProtocolError
from shared.mavlink.ftp.payload import (
    MAX_DATA,
    U32,
    DirEntry,
    FtpPayload,
    NakCode,
    Opcode,
    crc32_mavlink,
)


def _reply(request: FtpPayload, data: bytes = b"", nth: int = 0, burst_complete: bool = False,
           offset: int | None = None, opcode: Opcode = Opcode.ACK) -> FtpPayload:
    """A reply to ``request``: rule 1 (``nth`` counts the packets of a burst)."""
    return FtpPayload((request.seq + 1 + nth) & 0xFFFF, request.session, opcode, len(data),
                      request.opcode, burst_complete,
                      request.offset if offset is None else offset, data)


def _nak(request: FtpPayload, code: NakCode, errno_value: int = 0) -> FtpPayload:
    data = bytes([code, errno_value & 0xFF]) if code is NakCode.FAIL_ERRNO else bytes([code])
    return _reply(request, data, opcode=Opcode.NAK)


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
    """What the server serves. Refusals are ``OSError``\\ s (rule 3)."""

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
    """Rule 3."""
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
    """The vehicle's FTP server over a :class:`FtpFileSystem` (module rules).

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
        return [_reply(request, U32.pack(reader.size))]

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
        return [_reply(request, U32.pack(crc))]


def _chunk(request: FtpPayload) -> int:
    """Bytes per read reply: the size asked for, at most a packet (0 means a packet)."""
    return request.size if 0 < request.size <= MAX_DATA else MAX_DATA
