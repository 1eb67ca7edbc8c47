"""MAVLink FTP, ground side: the client, sans-I/O (payload codec: ``payload.py``).

Rules:

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

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from shared.config import FtpConfig
from shared.errors import LocalProtocolError, RemoteProtocolError
from shared.mavlink.ftp.payload import (
    MAX_DATA,
    U32,
    DirEntry,
    FtpPayload,
    NakCode,
    Opcode,
)


def _request(seq: int, session: int, opcode: Opcode, data: bytes = b"", offset: int = 0,
             size: int | None = None) -> FtpPayload:
    return FtpPayload(seq, session, opcode, len(data) if size is None else size,
                      offset=offset, data=data)


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
    """The server computed a file's :func:`~shared.mavlink.ftp.payload.crc32_mavlink`."""

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
    """The ground station's FTP client (module rules).

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
            size = U32.unpack_from(reply.data)[0]
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
            Opcode.CALC_FILE_CRC32: lambda: Checksummed(op.path, U32.unpack(op.data)[0]),
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
