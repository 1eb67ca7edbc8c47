"""Byte links: what the ARIA client and server talk through (DESIGN.md sec. 4, "Byte transports").

A :class:`ByteLink` is one end of a duplex byte stream that never blocks: ``write``
queues bytes for the peer, ``read_available`` returns what has arrived so far
(possibly nothing). Adapters wrap real transports (a pyserial URL, a pty, a TCP
socket); :func:`pipe_pair` gives two connected in-memory ends for lock-step runs
and tests, so the same protocol code runs over a wire and in one process.
"""

from __future__ import annotations

import threading
from typing import Protocol, runtime_checkable

from shared.errors import TransportError

__all__ = ["ByteLink", "LinkClosedError", "PipeEnd", "pipe_pair"]


class LinkClosedError(TransportError):
    """The transport under a byte link is gone (port unplugged, socket closed, pipe closed)."""


@runtime_checkable
class ByteLink(Protocol):
    """One end of a non-blocking duplex byte stream."""

    def write(self, data: bytes) -> None:
        """Queue ``data`` for the peer; raises :class:`LinkClosedError` if the link is gone."""
        ...

    def read_available(self) -> bytes:
        """Everything received since the last call (b"" if nothing); raises
        :class:`LinkClosedError` if the link is gone."""
        ...

    def close(self) -> None:
        """Release the transport; idempotent."""
        ...


class PipeEnd:
    """One end of an in-memory duplex pipe (made by :func:`pipe_pair`); thread-safe."""

    def __init__(self, inbox: bytearray, outbox: bytearray, lock: threading.Lock,
                 closed: list[bool]) -> None:
        self._inbox = inbox
        self._outbox = outbox
        self._lock = lock
        self._closed = closed

    def write(self, data: bytes) -> None:
        """Append ``data`` to the peer's inbox."""
        with self._lock:
            if self._closed[0]:
                raise LinkClosedError("pipe", "the in-memory pipe is closed")
            self._outbox += data

    def read_available(self) -> bytes:
        """Take everything the peer wrote since the last call."""
        with self._lock:
            if self._closed[0] and not self._inbox:
                raise LinkClosedError("pipe", "the in-memory pipe is closed")
            data = bytes(self._inbox)
            self._inbox.clear()
            return data

    def close(self) -> None:
        """Close both ends (bytes already written stay readable)."""
        with self._lock:
            self._closed[0] = True


def pipe_pair() -> tuple[PipeEnd, PipeEnd]:
    """Two connected in-memory ends: what one writes, the other reads.

    Returns:
        ``(a, b)``: ``a.write(x)`` makes ``x`` appear in ``b.read_available()`` and
        vice versa. Closing either end closes both.
    """
    a_to_b, b_to_a = bytearray(), bytearray()
    lock = threading.Lock()
    closed = [False]
    return PipeEnd(b_to_a, a_to_b, lock, closed), PipeEnd(a_to_b, b_to_a, lock, closed)
