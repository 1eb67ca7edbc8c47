"""The robot end's side of real transports in tests: a pty master and an accepted socket."""

from __future__ import annotations

import os
import socket
from collections.abc import Callable

from shared.byte_link import LinkClosedError
from shared.clock import WallClock
from tests.robot.pioneer.responder import Responder

POLL_NS = 2_000_000


class FdLink:
    """A non-blocking byte link on a file descriptor (the pty master)."""

    def __init__(self, fd: int) -> None:
        os.set_blocking(fd, False)
        self.fd = fd

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self.fd, view):]

    def read_available(self) -> bytes:
        try:
            return os.read(self.fd, 65536)
        except BlockingIOError:
            return b""

    def close(self) -> None:
        os.close(self.fd)


class SocketLink:
    """A non-blocking byte link on a connected TCP socket."""

    def __init__(self, sock: socket.socket) -> None:
        sock.setblocking(False)
        self.sock = sock

    def write(self, data: bytes) -> None:
        self.sock.sendall(data)

    def read_available(self) -> bytes:
        try:
            data = self.sock.recv(65536)
        except BlockingIOError:
            return b""
        if not data:
            raise LinkClosedError("tcp", "the driver closed the connection")
        return data

    def close(self) -> None:
        self.sock.close()


def serve_until(robot: Responder, done: Callable[[], bool], timeout_s: float = 5.0) -> None:
    """Service ``robot`` in real time until ``done()``; fail after ``timeout_s``."""
    clock = WallClock()
    deadline_ns = clock.now_ns() + round(timeout_s * 1e9)
    while not done():
        now_ns = clock.now_ns()
        assert now_ns < deadline_ns, "condition not reached in time"
        robot.service(now_ns)
        clock.sleep_until_ns(now_ns + POLL_NS)
