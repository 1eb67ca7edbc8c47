"""The in-memory byte pipe (shared/byte_link.py): duplex, ordered, closable, thread-safe."""

from __future__ import annotations

import threading

import pytest

from shared.byte_link import ByteLink, LinkClosedError, pipe_pair
from shared.errors import TransportError


def test_each_end_reads_what_the_other_wrote_in_order() -> None:
    a, b = pipe_pair()
    assert isinstance(a, ByteLink)
    a.write(b"\xfa\xfb")
    a.write(b"\x03")
    b.write(b"back")
    assert b.read_available() == b"\xfa\xfb\x03"
    assert b.read_available() == b""
    assert a.read_available() == b"back"


def test_closing_one_end_closes_both_after_the_pending_bytes() -> None:
    a, b = pipe_pair()
    a.write(b"last")
    b.close()
    with pytest.raises(LinkClosedError, match="closed"):
        a.write(b"more")
    assert b.read_available() == b"last"
    with pytest.raises(TransportError):
        b.read_available()
    a.close()  # idempotent


def test_concurrent_writers_lose_no_byte() -> None:
    a, b = pipe_pair()

    def write() -> None:
        for _ in range(1000):
            a.write(b"x")

    threads = [threading.Thread(target=write) for _ in range(4)]
    for thread in threads:
        thread.start()
    received = b""
    while any(t.is_alive() for t in threads):
        received += b.read_available()
    for thread in threads:
        thread.join()
    received += b.read_available()
    assert received == b"x" * 4000
