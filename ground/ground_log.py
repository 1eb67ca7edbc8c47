"""The ground log: every MAVLink packet the station receives or sends, in two files.

Theory of operation
-------------------

:class:`GroundLog` is a packet tap of :class:`~ground.station.GroundStation`
(``station.packet_taps``): each packet in or out reaches :meth:`GroundLog.record` with
its raw bytes, its parsed message and the station clock's reading, and goes to

1. ``<dir>/ground-NNNN.mcap`` through a :class:`~shared.logs.writer.LogWriter` named
   ``ground``: the message as JSON on ``/mavlink/<in|out>/<NAME>`` and its frame on
   ``/mavlink/raw`` (mcap-logging.md §3), ``log_time`` in Unix time (the station clock
   plus ``unix_offset_ns``, recorded in the ``clock`` metadata as in every log). The
   metadata record ``ground`` also holds ``unix_offset_ns`` and the name of the tlog, to
   line the two files up;
2. ``<dir>/ground-<stamp>.tlog`` (:class:`Tlog`), pymavlink's telemetry log that
   ``mavlogdump.py``, MAVExplorer, MAVProxy and QGroundControl read: per packet an 8-byte
   big-endian Unix time in µs, then the packet's bytes as on the wire. ``<stamp>`` is the
   UTC opening time, ``YYYYmmdd-HHMMSS``.

The tlog is written on the station's thread into a buffered file, flushed once its
oldest unflushed packet is ``LogConfig.flush_period_ns`` old (checked on every packet;
the station's own HEARTBEAT goes out every second while it runs, so a killed station
loses about a second at most) and on close. A write error (disk full) stops the tlog,
logged once and counted; it never stops the station.
"""

from __future__ import annotations

import contextlib
import logging
import os
import struct
import time
from pathlib import Path
from typing import IO

from shared.clock import Clock
from shared.config import LogConfig
from shared.errors import InputError
from shared.logs.writer import LogStats, LogWriter
from shared.mavlink.dialect import Message

log = logging.getLogger(__name__)

#: File name prefix of both files.
NAME = "ground"
#: A tlog record's header: Unix time, µs, unsigned 64-bit big-endian (pymavlink mavlogfile).
TLOG_HEADER = struct.Struct(">Q")
#: ``time.strftime`` format of the tlog's opening time (UTC) in its name.
STAMP_FORMAT = "%Y%m%d-%H%M%S"


def tlog_record(unix_us: int, packet: bytes) -> bytes:
    """One tlog record: ``unix_us`` (µs since 1970-01-01 UTC, >= 0) then ``packet``."""
    return TLOG_HEADER.pack(unix_us) + packet


def create_tlog(output_dir: Path, unix_ns: int) -> tuple[Path, IO[bytes]]:
    """Create ``<output_dir>/ground-<stamp>.tlog`` for a log opened at ``unix_ns`` (Unix
    ns); ``-2``, ``-3``... before ``.tlog`` when a run in the same second took the name.

    Returns:
        The path and the file, open for binary writing (buffered).

    Raises:
        InputError: the folder or the file cannot be created (names the folder).
    """
    stamp = time.strftime(STAMP_FORMAT, time.gmtime(unix_ns // 1_000_000_000))
    path = output_dir / f"{NAME}-{stamp}.tlog"
    try:
        output_dir.mkdir(parents=True, exist_ok=True)
        n = 1
        while True:
            try:
                return path, open(path, "xb")
            except FileExistsError:
                n += 1
                path = output_dir / f"{NAME}-{stamp}-{n}.tlog"
    except OSError as e:
        raise InputError(output_dir, f"cannot write the ground log: {e.strerror}") from None


class Tlog:
    """A pymavlink telemetry log being written (module docstring); owns ``file``.

    Args:
        path: the file's name (for messages).
        file: the file, open for binary writing (e.g. from :func:`create_tlog`).
        flush_period_ns: flush once the oldest unflushed record is this old, ns.
        fsync: also ``os.fsync`` after each flush.
    """

    def __init__(self, path: Path, file: IO[bytes], flush_period_ns: int, fsync: bool) -> None:
        self.path = path
        self._file: IO[bytes] | None = file
        self._flush_period_ns = flush_period_ns
        self._fsync = fsync
        self._pending = 0
        self._pending_since_ns: int | None = None
        self.records = 0
        """Records flushed to the file."""
        self.lost = 0
        """Records lost to a file error (all those unflushed when it happened, and later)."""

    def write(self, unix_ns: int, packet: bytes, now_ns: int) -> None:
        """Append ``packet`` sent or received at ``unix_ns``.

        Args:
            unix_ns: the packet's time, Unix ns (stored in µs).
            packet: the MAVLink frame as on the wire.
            now_ns: a monotonic clock's reading, ns, for the flush period.
        """
        if self._file is None:
            self.lost += 1
            return
        self._pending += 1
        if self._pending_since_ns is None:
            self._pending_since_ns = now_ns
        try:
            self._file.write(tlog_record(unix_ns // 1000, packet))
            if now_ns - self._pending_since_ns >= self._flush_period_ns:
                self._flush()
        except OSError as e:
            self._fail(e)

    def _flush(self) -> None:
        assert self._file is not None
        self._file.flush()
        if self._fsync:
            os.fsync(self._file.fileno())
        self.records += self._pending
        self._pending, self._pending_since_ns = 0, None

    def _fail(self, error: OSError) -> None:
        log.error("%s: tlog stopped, %d records lost: %s", self.path, self._pending,
                  error.strerror or error)
        self.lost += self._pending
        self._pending, self._pending_since_ns = 0, None
        file, self._file = self._file, None
        if file is not None:
            with contextlib.suppress(OSError):  # its buffer is lost either way
                file.close()

    def close(self) -> None:
        """Flush and close the file; idempotent."""
        if self._file is None:
            return
        try:
            self._flush()
            self._file.close()
            self._file = None
        except OSError as e:
            self._fail(e)


class GroundLog:
    """The ground station's MCAP log and tlog (module docstring).

    Args:
        config: the folder (``output_dir``), flushing and rotation; the MCAP files are
            ``ground-NNNN.mcap``.
        clock: the station's clock (the time :meth:`record` is given).
        unix_offset_ns: Unix time minus ``clock``'s reading, ns (the tlog's times).

    Raises:
        InputError: the tlog cannot be created in ``config.output_dir``.
    """

    def __init__(self, config: LogConfig, clock: Clock, unix_offset_ns: int) -> None:
        self.unix_offset_ns = unix_offset_ns
        self.tlog = Tlog(*create_tlog(Path(config.output_dir), clock.now_ns() + unix_offset_ns),
                         config.flush_period_ns, config.fsync)
        self.writer = LogWriter(config, name=NAME, unix_offset_ns=unix_offset_ns)
        self.writer.add_metadata(NAME, {"unix_offset_ns": str(unix_offset_ns),
                                        "tlog": self.tlog.path.name})

    def record(self, direction: str, packet: bytes, msg: Message, now_ns: int) -> None:
        """Log one packet (a :data:`ground.station.PacketTap`).

        Args:
            direction: ``"in"`` (received) or ``"out"`` (sent).
            packet: its bytes as on the wire.
            msg: the message it holds, parsed or packed (its frame is ``packet``).
            now_ns: the station clock, ns.
        """
        self.writer.log_mavlink(now_ns, msg, direction)
        self.tlog.write(now_ns + self.unix_offset_ns, packet, now_ns)

    def close(self) -> LogStats:
        """Finish both files; the MCAP writer's counters. Idempotent."""
        self.tlog.close()
        return self.writer.close()

    def summary_text(self, stats: LogStats) -> str:
        """``logged N packets to DIR/ground-0001.mcap, DIR/ground-<stamp>.tlog``: what the
        closed log holds (``stats`` from :meth:`close`; N the tlog's packets)."""
        files = ", ".join(str(path) for path in (*stats.files, self.tlog.path))
        return f"logged {self.tlog.records} packets to {files}"

    def __enter__(self) -> GroundLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
