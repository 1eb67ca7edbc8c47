"""The guarded HTTP server on real sockets: busy handlers, idle and slow clients, errors."""

from __future__ import annotations

import json
import logging
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from shared.guarded_http import GuardedHandler, GuardedHTTPServer, HttpLimits, RequestRefusedError
from tests.sim.camera_stream import eventually

RELEASE = threading.Event()
"""GET /hold waits for it: a handler kept busy as long as the test wants."""


class EchoHandler(GuardedHandler):
    """GET /hold waits for RELEASE; GET /boom raises; POST echoes its JSON body."""

    def do_GET(self) -> None:  # noqa: N802 - http.server names the method
        if (refused := self.refusal()) is not None:
            self._reply(refused.status, refused.reason.encode())
            return
        if self.path == "/boom":
            raise ZeroDivisionError("a bug")
        if self.path == "/hold":
            RELEASE.wait(10.0)
        self._reply(200, b"{}")

    def do_POST(self) -> None:  # noqa: N802 - http.server names the method
        try:
            self._reply(200, json.dumps(self.read_json()).encode())
        except RequestRefusedError as e:
            self._reply(e.status, e.reason.encode())

    def _reply(self, status: int, body: bytes) -> None:
        self.send_response(status)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:
        """Quiet."""


@contextmanager
def serving(limits: HttpLimits) -> Iterator[GuardedHTTPServer]:
    server = GuardedHTTPServer(("127.0.0.1", 0), EchoHandler, limits)
    thread = threading.Thread(target=server.serve_forever, args=(0.05,))
    thread.start()
    try:
        yield server
    finally:
        RELEASE.set()
        server.shutdown()
        server.server_close()
        thread.join()
        RELEASE.clear()


def request(server: GuardedHTTPServer, raw: bytes) -> bytes:
    """Send ``raw`` on a new connection; everything the server answers before closing."""
    with socket.create_connection(server.server_address, timeout=10.0) as conn:
        conn.sendall(raw)
        reply = b""
        while chunk := conn.recv(4096):
            reply += chunk
        return reply


def post(body: bytes, content_type: str = "application/json") -> bytes:
    return (f"POST / HTTP/1.0\r\nContent-Type: {content_type}\r\n"
            f"Content-Length: {len(body)}\r\n\r\n").encode() + body


def test_a_request_while_every_handler_is_busy_gets_503_at_once() -> None:
    with serving(HttpLimits(max_handlers=1)) as server:
        held = socket.create_connection(server.server_address)
        held.sendall(b"GET /hold HTTP/1.0\r\n\r\n")
        assert eventually(lambda: server.stats().handling == 1)
        assert request(server, b"GET / HTTP/1.0\r\n\r\n").startswith(b"HTTP/1.0 503")
        RELEASE.set()
        assert held.recv(100).startswith(b"HTTP/1.0 200")
        held.close()
        assert eventually(lambda: server.stats().handling == 0)
        assert request(server, b"GET / HTTP/1.0\r\n\r\n").startswith(b"HTTP/1.0 200")
        assert server.stats().busy_refused == 1


def test_connections_that_send_nothing_are_closed_after_the_idle_timeout() -> None:
    with serving(HttpLimits(idle_timeout_s=0.2)) as server:
        idle = socket.create_connection(server.server_address, timeout=10.0)
        assert idle.recv(1) == b""  # closed by the server
        idle.close()
        assert server.stats().idle_closed == 1


def test_beyond_max_waiting_the_oldest_waiting_connection_is_closed() -> None:
    with serving(HttpLimits(max_waiting=3)) as server:
        conns = [socket.create_connection(server.server_address, timeout=10.0)
                 for _ in range(5)]
        assert eventually(lambda: server.stats().overflow_closed == 2)
        assert conns[0].recv(1) == b"" and conns[1].recv(1) == b""
        conns[4].sendall(b"GET / HTTP/1.0\r\n\r\n")
        assert conns[4].recv(100).startswith(b"HTTP/1.0 200")
        for conn in conns:
            conn.close()


def test_a_handler_exception_ends_its_request_only_and_is_logged_once(
        caplog: pytest.LogCaptureFixture) -> None:
    with serving(HttpLimits()) as server, caplog.at_level(logging.WARNING, "shared.guarded_http"):
        for _ in range(3):
            request(server, b"GET /boom HTTP/1.0\r\n\r\n")
        assert request(server, b"GET / HTTP/1.0\r\n\r\n").startswith(b"HTTP/1.0 200")
        assert server.stats().handler_errors == 3
    logged = [r.getMessage() for r in caplog.records]
    assert len(logged) == 1 and "ZeroDivisionError: a bug" in logged[0]


@pytest.mark.parametrize("raw, status", [
    (post(b'{"a": [1, 2]}'), b"200"),
    (post(b'{"a": 1}', "application/json; charset=utf-8"), b"200"),
    (post(b'{"a": 1}', "text/plain"), b"415"),
    (b"POST / HTTP/1.0\r\nContent-Type: application/json\r\n\r\n{}", b"411"),
    (post(b" " * 5000), b"413"),
    (post(b"\xff\xfe"), b"400"),
    (post(b"[" * 3000 + b"]" * 1000), b"400"),
])
def test_json_bodies(raw: bytes, status: bytes) -> None:
    with serving(HttpLimits()) as server:
        assert request(server, raw).startswith(b"HTTP/1.0 " + status)


def test_a_body_that_does_not_arrive_in_time_is_408() -> None:
    with (serving(HttpLimits(handler_timeout_s=0.3)) as server,
          socket.create_connection(server.server_address, timeout=10.0) as conn):
        conn.sendall(post(b'{"a": 1}')[:-3])  # three bytes short, never sent
        assert conn.recv(100).startswith(b"HTTP/1.0 408")


@pytest.mark.parametrize("headers, status", [
    ("", b"200"),  # no Host (HTTP/1.0): no browser sent it
    ("Host: localhost:8080\r\n", b"200"),
    ("Host: LOCALHOST\r\n", b"200"),
    ("Host: 127.0.0.2:8080\r\n", b"200"),
    ("Host: [::1]:8080\r\n", b"200"),
    ("Host: 127.0.0.1:8080\r\nOrigin: http://127.0.0.1:8080\r\n", b"200"),
    ("Host: 10.0.0.7:8080\r\n", b"403"),
    ("Host: attacker.example\r\n", b"403"),
    ("Host: 127.0.0.1:8080\r\nOrigin: http://127.0.0.1:9999\r\n", b"403"),
    ("Origin: http://127.0.0.1:8080\r\n", b"403"),  # an Origin without a Host to match
])
def test_host_and_origin_on_a_loopback_server(headers: str, status: bytes) -> None:
    with serving(HttpLimits()) as server:
        raw = f"GET / HTTP/1.0\r\n{headers}\r\n".encode()
        assert request(server, raw).startswith(b"HTTP/1.0 " + status)
