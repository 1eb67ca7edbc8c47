"""HTTP serving guarded against a hostile client on the same machine or net.

:class:`GuardedHTTPServer` is a :class:`~http.server.ThreadingHTTPServer` whose threads
are bounded; :class:`GuardedHandler` adds the request checks its handlers share. The
MJPEG cameras (:mod:`shared.mjpeg_server`: the simulator's network camera and the
robot's ``vmnav robot --video``) and the simulator's control endpoint
(:mod:`sim.control_server`) serve on it.

Rules:

1. **A lobby, not a thread, per idle connection.** An accepted connection waits in the
   lobby (one thread, one selector) until its first byte arrives; only then does a
   handler thread take it. So 300 connections that send nothing cost 300 sockets and
   no thread. One that sends nothing for ``idle_timeout_s`` is closed; beyond
   ``max_waiting`` waiting connections, the oldest is closed.
2. **Bounded handler threads.** At most ``max_handlers`` requests are handled at once;
   a connection whose bytes arrive while all are busy gets ``503`` at once and is
   closed. A handler's socket operations time out after ``handler_timeout_s``, and a
   request body must arrive within that time in all.
3. **Same origin.** A request with an ``Origin`` header that is not the server's own
   (``http://`` + its ``Host``) is refused (403): a web page of another site cannot
   use the server through the visitor's browser. A server bound to a loopback address
   also refuses a ``Host`` that is not ``localhost`` or a loopback address (403), so a
   DNS-rebound name cannot pass as the server's own origin.
4. **JSON bodies only.** :meth:`GuardedHandler.read_json` takes only ``Content-Type:
   application/json`` (415 otherwise; this also makes every cross-origin POST from a
   browser need a CORS preflight, which is never granted), with a ``Content-Length``
   (411) of at most ``max_body_bytes`` (413), that parses as JSON (400, also for
   nesting too deep or numbers out of range).
5. An exception in a handler ends that request only; it is counted and logged once per
   kind (:attr:`GuardedHTTPServer.handler_errors`).
"""

from __future__ import annotations

import contextlib
import ipaddress
import json
import logging
import selectors
import socket
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

from shared.handler_faults import HandlerFaults

log = logging.getLogger(__name__)

_BUSY_REPLY = (b"HTTP/1.0 503 Service Unavailable\r\nContent-Type: text/plain\r\n"
               b"Content-Length: 33\r\nConnection: close\r\n\r\n"
               b"busy: every handler thread in use")
"""Sent from the lobby, without a thread, to a connection no handler can take (rule 2)."""
_LOOPBACK_NAMES = frozenset({"localhost"})


@dataclass(frozen=True, slots=True)
class HttpLimits:
    """What one client may take of a :class:`GuardedHTTPServer` (see the module rules).

    Attributes:
        max_handlers: requests handled at once, one thread each.
        max_waiting: connections waiting for their first byte.
        idle_timeout_s: a waiting connection that sent nothing for this long is closed, s.
        handler_timeout_s: a handler's socket operations, and a whole request body, s.
        max_body_bytes: the largest request body taken, bytes.
    """

    max_handlers: int = 8
    max_waiting: int = 128
    idle_timeout_s: float = 10.0
    handler_timeout_s: float = 5.0
    max_body_bytes: int = 4096


@dataclass(frozen=True, slots=True)
class LobbyStats:
    """Counts of a server's lobby (rules 1-2).

    Attributes:
        waiting: connections waiting for their first byte now.
        handling: requests being handled now (handler threads alive).
        idle_closed: connections closed for sending nothing within the idle timeout.
        overflow_closed: the oldest waiting connections closed to make room.
        busy_refused: connections answered 503 because every handler was busy.
        handler_errors: exceptions that ended a request (rule 5).
    """

    waiting: int
    handling: int
    idle_closed: int
    overflow_closed: int
    busy_refused: int
    handler_errors: int


class RequestRefusedError(Exception):
    """A request the server will not take: an HTTP status and a one-line reason."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason


class _Lobby:
    """Rule 1: accepted connections waiting for their first byte, on one thread."""

    def __init__(self, limits: HttpLimits, ready: Callable[[socket.socket, Any], None],
                 close: Callable[[socket.socket], None], name: str) -> None:
        self._limits = limits
        self._ready, self._close = ready, close
        self._selector = selectors.DefaultSelector()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._selector.register(self._wake_r, selectors.EVENT_READ)
        self._lock = threading.Lock()
        self._incoming: list[tuple[socket.socket, Any]] = []
        self._waiting: dict[socket.socket, tuple[Any, float]] = {}  # oldest first
        self._closing = False
        self.idle_closed = self.overflow_closed = 0
        self._thread = threading.Thread(target=self._run, name=f"{name}-lobby", daemon=True)
        self._thread.start()

    @property
    def waiting(self) -> int:
        with self._lock:
            return len(self._waiting) + len(self._incoming)

    def admit(self, conn: socket.socket, address: Any) -> None:
        """A new connection (from the accept loop's thread)."""
        with self._lock:
            if self._closing:
                self._close(conn)
                return
            self._incoming.append((conn, address))
        self._wake()

    def close(self) -> None:
        """Close every waiting connection and join the lobby's thread; idempotent."""
        with self._lock:
            self._closing = True
        self._wake()
        self._thread.join()

    def _wake(self) -> None:
        with contextlib.suppress(OSError):  # full (a wake-up is pending anyway) or closed
            self._wake_w.send(b"\0")

    def _run(self) -> None:
        try:
            while self._serve_once():
                pass
        finally:
            for conn in [*self._waiting, *(c for c, _ in self._incoming)]:
                self._close(conn)
            self._selector.close()
            self._wake_r.close()
            self._wake_w.close()

    def _serve_once(self) -> bool:
        """Take new connections, hand on the ready ones, close the idle; False once closing."""
        with self._lock:
            if self._closing:
                return False
            incoming, self._incoming = self._incoming, []
        now = time.monotonic()
        for conn, address in incoming:
            self._waiting[conn] = (address, now + self._limits.idle_timeout_s)
            self._selector.register(conn, selectors.EVENT_READ)
        timeout = None
        if incoming:  # look for their bytes, then make room (below), before waiting
            timeout = 0.0
        elif self._waiting:
            oldest_deadline = next(iter(self._waiting.values()))[1]
            timeout = max(0.0, oldest_deadline - now)
        for key, _ in self._selector.select(timeout):
            conn = key.fileobj
            if conn is self._wake_r:
                with contextlib.suppress(BlockingIOError):
                    self._wake_r.recv(4096)
                continue
            assert isinstance(conn, socket.socket)
            address, _ = self._waiting.pop(conn)
            self._selector.unregister(conn)
            self._ready(conn, address)
        while len(self._waiting) > self._limits.max_waiting:  # after the ready ones left
            self.overflow_closed += 1  # counted before the client can see it
            self._drop(next(iter(self._waiting)))
        now = time.monotonic()
        for conn, (_, deadline) in list(self._waiting.items()):
            if deadline > now:
                break  # in arrival order: the rest are younger
            self.idle_closed += 1
            self._drop(conn)
        return True

    def _drop(self, conn: socket.socket) -> None:
        del self._waiting[conn]
        self._selector.unregister(conn)
        self._close(conn)


class GuardedHTTPServer(ThreadingHTTPServer):
    """A ThreadingHTTPServer with a lobby and bounded handler threads (rules 1, 2, 5).

    Handler threads are joined at :meth:`server_close`.

    Args:
        address: (host, port) to bind; port 0 picks a free one.
        handler: the request handler class, a :class:`GuardedHandler`.
        limits: what one client may take.

    Raises:
        OSError: the address cannot be bound.
    """

    daemon_threads = False
    request_queue_size = 64  # the accept loop hands connections on at once

    def __init__(self, address: tuple[str, int], handler: type[GuardedHandler],
                 limits: HttpLimits) -> None:
        self.limits = limits
        self.loopback_only = is_loopback_name(address[0])
        self._slots = threading.BoundedSemaphore(limits.max_handlers)
        self._counts_lock = threading.Lock()
        self._handling = self._busy_refused = 0
        self._faults = HandlerFaults(log, f"HTTP server on port {address[1]}",
                                     level=logging.WARNING, traceback=False)
        self._lobby = _Lobby(limits, self._take, self.shutdown_request, f"http-{address[1]}")
        super().__init__(address, handler)  # if it cannot bind, its server_close ends the lobby

    def stats(self) -> LobbyStats:
        """The lobby's counts now."""
        with self._counts_lock:
            return LobbyStats(self._lobby.waiting, self._handling, self._lobby.idle_closed,
                              self._lobby.overflow_closed, self._busy_refused,
                              self._faults.total)

    def process_request(self, request: Any, client_address: Any) -> None:
        """The accept loop's connection goes to the lobby (rule 1)."""
        self._lobby.admit(request, client_address)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        """One handler thread; its slot is freed when it ends (rule 2)."""
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self._counts_lock:
                self._handling -= 1
            self._slots.release()

    def handle_error(self, request: Any, client_address: Any) -> None:
        """Rule 5: count; log the first error of each kind, without a traceback."""
        self._faults.record("request", _current_exception())

    def server_close(self) -> None:
        """Close the waiting connections and the socket; join the handler threads."""
        self._lobby.close()
        super().server_close()

    def _take(self, conn: socket.socket, address: Any) -> None:
        """A waiting connection sent bytes: a handler thread, or 503 if none is free."""
        if not self._slots.acquire(blocking=False):
            with self._counts_lock:
                self._busy_refused += 1
            conn.setblocking(False)
            with contextlib.suppress(OSError):  # gone, or its buffer is full: closing says enough
                conn.send(_BUSY_REPLY)
            self.shutdown_request(conn)
            return
        with self._counts_lock:
            self._handling += 1
        try:
            super().process_request(conn, address)
        except RuntimeError as e:  # the system would start no thread: this request only fails
            with self._counts_lock:
                self._handling -= 1
                self._handler_errors += 1
            self._slots.release()
            log.warning("HTTP request from %s dropped: %s", address, e)
            self.shutdown_request(conn)


class GuardedHandler(BaseHTTPRequestHandler):
    """Request checks for the handlers of a :class:`GuardedHTTPServer` (rules 2-4)."""

    server: GuardedHTTPServer

    def setup(self) -> None:
        self.timeout = self.server.limits.handler_timeout_s
        super().setup()

    def refusal(self) -> RequestRefusedError | None:
        """Rule 3: why this request's ``Host`` or ``Origin`` is refused; None if it is not."""
        host = self.headers.get("Host")
        if host is not None and self.server.loopback_only and not is_loopback_name(
                host_name_of(host)):
            return RequestRefusedError(403, f"Host {host!r} is not this machine's loopback")
        origin = self.headers.get("Origin")
        if origin is not None and (host is None or origin.lower() != f"http://{host}".lower()):
            return RequestRefusedError(403, f"cross-origin request from {origin!r} refused")
        return None

    def read_json(self) -> Any:
        """The request body as JSON (rules 2 and 4).

        Raises:
            RequestRefusedError: not ``application/json`` (415), no length (411), too long
                (413), not received in time (408), or not JSON (400).
        """
        if self.headers.get_content_type() != "application/json":
            raise RequestRefusedError(415, "the body must be Content-Type: application/json, not "
                                      f"{self.headers.get('Content-Type')!r}")
        limit = self.server.limits.max_body_bytes
        try:
            length = int(self.headers.get("Content-Length", ""))
        except ValueError:
            raise RequestRefusedError(411, "a Content-Length is needed") from None
        if not 0 <= length <= limit:
            raise RequestRefusedError(413, f"a body of {length} bytes; at most {limit} are taken")
        body = self._read_body(length)
        try:
            return json.loads(body)
        except (ValueError, RecursionError) as e:  # UnicodeDecodeError is a ValueError
            raise RequestRefusedError(400, f"the body is not JSON: {_one_line(e)}") from None

    def _read_body(self, length: int) -> bytes:
        deadline = time.monotonic() + self.server.limits.handler_timeout_s
        body = bytearray()
        try:
            while len(body) < length:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise TimeoutError
                self.connection.settimeout(remaining)
                chunk = self.rfile.read1(length - len(body))
                if not chunk:
                    raise RequestRefusedError(400, f"the body ended after {len(body)} of "
                                              f"{length} bytes")
                body += chunk
        except TimeoutError:
            raise RequestRefusedError(408, f"the body did not arrive within "
                                      f"{self.server.limits.handler_timeout_s:g} s") from None
        return bytes(body)


def is_loopback_name(host: str) -> bool:
    """Whether ``host`` (a name or an address) means this machine only (also the web app's
    check, ``ground.web.access``)."""
    if host.lower() in _LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def host_name_of(host_header: str) -> str:
    """The name or address of a ``Host`` header, without its port and IPv6 brackets."""
    if host_header.startswith("["):
        return host_header[1:].partition("]")[0]
    return host_header.rpartition(":")[0] if host_header.count(":") == 1 else host_header


def _one_line(error: BaseException) -> str:
    return str(error).splitlines()[0] if str(error) else type(error).__name__


def _current_exception() -> Exception:
    """The exception being handled (``handle_error`` is called inside an ``except``)."""
    error = sys.exc_info()[1]
    return error if isinstance(error, Exception) else RuntimeError(f"{error!r}")
