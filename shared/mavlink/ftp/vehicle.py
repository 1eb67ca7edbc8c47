"""MAVLink FTP, vehicle side: the server, sans-I/O (payload codec: ``payload.py``).

Rules:

1. A reply has ``seq`` = request seq + 1 (the packets of a burst count on: +1, +2,
   ...), ``req_opcode`` = the request's opcode, and **the request's session byte**,
   also on OpenFileRO/CreateFile/OpenFileWO: MAVProxy picks the session byte and
   drops replies carrying another one (§0.6).
2. A request byte-identical to the previous one from the same peer is a retry after
   a lost reply: the cached reply goes out again and nothing runs twice (a retried
   CreateFile must not fail with FileExists). The cache keeps the last one-reply
   exchange of at most ``resend_cache_peers`` peers, the least recently used
   forgotten first, so it stays under ``resend_cache_peers`` x 2 x 251 bytes of
   payload whatever the number of peers. Not cached: NoSessionsAvailable (the client
   is meant to retry until a session frees) and bursts (a retried BurstReadFile
   reads again, which is idempotent).
3. Policy lives in the :class:`FtpFileSystem`. Its ``OSError``\\ s become NAKs:
   FileNotFoundError/NotADirectoryError -> FileNotFound, PermissionError/EROFS ->
   FileProtected, FileExistsError -> FileExists, another errno -> FailErrno.
4. ArduPilot's virtual files (``@PARAM/param.pck``, ``@MISSION/...``, ``@SYS/...``)
   get FileNotFound at once, so MAVProxy falls back to PARAM_REQUEST_LIST (§0.8).
5. At most ``max_sessions`` sessions are open; one unused for ``session_timeout_ns``
   is closed (an upload discarded) when the next request arrives. TerminateSession
   commits an upload; ResetSessions closes the sessions of its sender (discarding its
   uploads in progress).
6. A session belongs to the peer that opened it: sessions are looked up by (peer,
   session byte), so another peer's request for the same session byte gets
   InvalidSession (it cannot read, write, commit or close it), and an open from
   another peer with that byte opens a session of its own.
7. Amplification: every request gets exactly one reply, except a BurstReadFile on a
   session its sender owns, which gets at most ``burst_packets`` (the protocol's
   burst; fewer at the end of the file). A stranger's request costs one packet.
"""

from __future__ import annotations

import errno
from collections import OrderedDict
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


#: A server operation: (request, its sender, now_ns) -> replies; raises _NakError or OSError.
_Handler = Callable[[FtpPayload, Hashable, int], list[FtpPayload]]


class FtpServer:
    """The vehicle's FTP server over a :class:`FtpFileSystem` (module rules).

    Args:
        fs: what to serve.
        config: session limits and burst length.
    """

    def __init__(self, fs: FtpFileSystem, config: FtpConfig | None = None) -> None:
        self.fs = fs
        self.config = config if config is not None else FtpConfig()
        self._sessions: dict[tuple[Hashable, int], _Session] = {}
        self._last: OrderedDict[Hashable, tuple[bytes, bytes]] = OrderedDict()
        self._handlers: dict[int, _Handler] = {
            Opcode.NONE: lambda r, peer, now: [_reply(r)],
            Opcode.TERMINATE_SESSION: self._terminate,
            Opcode.RESET_SESSIONS: self._reset,
            Opcode.LIST_DIRECTORY: self._list,
            Opcode.OPEN_FILE_RO: self._open_ro,
            Opcode.READ_FILE: self._read,
            Opcode.BURST_READ_FILE: self._burst,
            Opcode.CREATE_FILE: lambda r, peer, now: self._open_wo(r, peer, now, exclusive=True),
            Opcode.OPEN_FILE_WO: lambda r, peer, now: self._open_wo(r, peer, now,
                                                                    exclusive=False),
            Opcode.WRITE_FILE: self._write,
            Opcode.REMOVE_FILE: self._remove,
            Opcode.CALC_FILE_CRC32: self._crc,
        }

    @property
    def open_sessions(self) -> int:
        """Sessions open now."""
        return len(self._sessions)

    @property
    def cached_peers(self) -> int:
        """Peers whose last exchange the resend cache holds (rule 2)."""
        return len(self._last)

    def handle(self, payload: bytes | Sequence[int], now_ns: int,
               peer: Hashable = None) -> list[bytes]:
        """Answer one request.

        Args:
            payload: the request's payload field.
            now_ns: when it arrived, ns (session time-outs).
            peer: who sent it, e.g. ``(sysid, compid)``; keys the retry cache (rule 2)
                and owns the sessions it opens (rule 6).

        Returns:
            Reply payload fields (251 bytes each) in sending order; several only for a
            burst read (rule 7), none for a payload too short to parse.
        """
        raw = bytes(payload)
        cached = self._last.get(peer)
        if cached is not None and cached[0] == raw:
            self._last.move_to_end(peer)
            return [cached[1]]
        try:
            request = FtpPayload.from_bytes(raw)
        except RemoteProtocolError:
            return []
        self._expire(now_ns)
        handler = self._handlers.get(request.opcode)
        try:
            if handler is None:
                raise _NakError(NakCode.UNKNOWN_COMMAND)
            replies = handler(request, peer, now_ns)
        except _NakError as e:
            replies = [_nak(request, e.code)]
        except OSError as e:
            replies = [_nak_for(request, e)]
        out = [reply.to_bytes() for reply in replies]
        # a retry of NoSessionsAvailable may succeed; a burst is read again (rule 2)
        if len(out) == 1 and replies[0].data != bytes([NakCode.NO_SESSIONS_AVAILABLE]):
            self._remember(peer, raw, out[0])
        return out

    def _remember(self, peer: Hashable, request: bytes, reply: bytes) -> None:
        """Cache ``peer``'s last exchange, forgetting the least recently used (rule 2)."""
        self._last[peer] = (request, reply)
        self._last.move_to_end(peer)
        while len(self._last) > self.config.resend_cache_peers:
            self._last.popitem(last=False)

    def _expire(self, now_ns: int) -> None:
        for key, session in list(self._sessions.items()):
            if now_ns - session.last_used_ns >= self.config.session_timeout_ns:
                del self._sessions[key]
                session.close(commit=False)

    def _session(self, request: FtpPayload, peer: Hashable, now_ns: int) -> _Session:
        """The sender's session the request names (rule 6)."""
        session = self._sessions.get((peer, request.session))
        if session is None:
            raise _NakError(NakCode.INVALID_SESSION)
        session.last_used_ns = now_ns
        return session

    def _add_session(self, request: FtpPayload, peer: Hashable, session: _Session) -> None:
        """Give ``session`` the sender and the request's id (rules 1 and 6), replacing a
        stale one of the same sender."""
        old = self._sessions.pop((peer, request.session), None)
        if old is not None:
            old.close(commit=False)
        if len(self._sessions) >= self.config.max_sessions:
            session.close(commit=False)
            raise _NakError(NakCode.NO_SESSIONS_AVAILABLE)
        self._sessions[(peer, request.session)] = session

    def _terminate(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        self._session(request, peer, now_ns)
        self._sessions.pop((peer, request.session)).close(commit=True)
        return [_reply(request)]

    def close(self) -> None:
        """Close every session, discarding uploads in progress (shutdown)."""
        sessions, self._sessions = self._sessions, {}
        for session in sessions.values():
            session.close(commit=False)

    def _reset(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        """ResetSessions: the sender's sessions only (rule 5)."""
        for key in [key for key in self._sessions if key[0] == peer]:
            self._sessions.pop(key).close(commit=False)
        return [_reply(request)]

    def _list(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
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

    def _open_ro(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        reader = self.fs.open_read(_path(request))
        self._add_session(request, peer, _Session(now_ns, reader=reader))
        return [_reply(request, U32.pack(reader.size))]

    def _open_wo(self, request: FtpPayload, peer: Hashable, now_ns: int,
                 exclusive: bool) -> list[FtpPayload]:
        writer = self.fs.open_write(_path(request), exclusive)
        self._add_session(request, peer, _Session(now_ns, writer=writer))
        return [_reply(request)]

    def _reader(self, request: FtpPayload, peer: Hashable, now_ns: int) -> FtpReader:
        reader = self._session(request, peer, now_ns).reader
        if reader is None:
            raise _NakError(NakCode.INVALID_SESSION)
        if request.offset >= reader.size:
            raise _NakError(NakCode.EOF)
        return reader

    def _read(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        reader = self._reader(request, peer, now_ns)
        return [_reply(request, reader.read(request.offset, _chunk(request)))]

    def _burst(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        reader = self._reader(request, peer, now_ns)
        replies, offset, chunk = [], request.offset, _chunk(request)
        for nth in range(self.config.burst_packets):
            data = reader.read(offset, chunk)
            last = offset + len(data) >= reader.size or nth == self.config.burst_packets - 1
            replies.append(_reply(request, data, nth, burst_complete=last, offset=offset))
            offset += len(data)
            if last:
                break
        return replies

    def _write(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        writer = self._session(request, peer, now_ns).writer
        if writer is None:
            raise _NakError(NakCode.INVALID_SESSION)
        if request.size > MAX_DATA:
            raise _NakError(NakCode.INVALID_DATA_SIZE)
        writer.write(request.offset, request.data)
        return [_reply(request)]

    def _remove(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
        self.fs.remove(_path(request))
        return [_reply(request)]

    def _crc(self, request: FtpPayload, peer: Hashable, now_ns: int) -> list[FtpPayload]:
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
