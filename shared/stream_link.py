"""Byte links over OS streams: a file descriptor, a TCP connection, a TCP listener.

Used by the emulated Pioneer (``sim.pioneer``: its pty and TCP clients), by the robot's
ARIA client over TCP (``robot.pioneer.serial_link``) and by MAVLink over TCP (the
robot's ``robot.vehicle.stream_vehicle`` and the ground station's
``ground.stream_port``).

The links are :class:`shared.byte_link.ByteLink` adapters, non-blocking, each owning
its file descriptor or socket. A write the kernel cannot take at once is dropped and
counted (``dropped_bytes``), as bytes are lost on a serial line nobody reads; the
reader's deframer resyncs on the next packet. OS errors become
:class:`~shared.byte_link.LinkClosedError` (a link that went away) or
:class:`~shared.errors.TransportError` (one that cannot be opened, in one line naming
it). :func:`connect_tcp` gives up after a short timeout, so an unreachable host is an
error in about a second rather than the kernel's minutes.
"""

from __future__ import annotations

import os
import socket
from collections.abc import Callable

from shared.byte_link import LinkClosedError
from shared.errors import TransportError
from shared.ipv4 import resolve_ipv4

__all__ = ["CONNECT_TIMEOUT_S", "READ_LIMIT", "StreamLink", "TcpListener", "connect_tcp", "fd_io"]

_READ_CHUNK = 4096
READ_LIMIT = 65536
"""Most bytes one :meth:`StreamLink.read_available` returns (the rest waits for the next
call): a client that sends without pause cannot hold a tick for ever. A serial line at
115200 baud carries about 11.5 kB/s."""
CONNECT_TIMEOUT_S = 1.5
"""How long :func:`connect_tcp` waits for a host to answer, s: a host on the LAN answers
within milliseconds; one that does not is reported well under 2 s."""


class StreamLink:
    """A :class:`~shared.byte_link.ByteLink` over a non-blocking OS stream.

    Build one with :meth:`from_fd` or :meth:`from_socket`.

    Args:
        where: the transport, for messages (``/dev/pts/3``, ``tcp:127.0.0.1:50312``).
        recv: reads up to n bytes; b"" at end of stream; raises BlockingIOError when empty.
        send: writes bytes, returns how many it took; raises BlockingIOError when full.
        release: closes the descriptor.
        fd: the descriptor, for ``select`` (:meth:`fileno`).
    """

    def __init__(
        self,
        where: str,
        recv: Callable[[int], bytes],
        send: Callable[[bytes], int],
        release: Callable[[], None],
        fd: int = -1,
    ) -> None:
        self.where = where
        self._fd = fd
        self.dropped_bytes = 0
        """Bytes written while the kernel's buffer was full, and so lost."""
        self._recv, self._send, self._release = recv, send, release
        self._closed = False

    @classmethod
    def from_fd(cls, fd: int, where: str) -> StreamLink:
        """A link owning file descriptor ``fd`` (made non-blocking)."""
        os.set_blocking(fd, False)
        return cls(where, *fd_io(fd), release=lambda: os.close(fd), fd=fd)

    @classmethod
    def from_socket(cls, sock: socket.socket, where: str) -> StreamLink:
        """A link owning connected stream socket ``sock`` (made non-blocking, no Nagle delay)."""
        sock.setblocking(False)
        if sock.family in (socket.AF_INET, socket.AF_INET6):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return cls(where, sock.recv, sock.send, lambda: _close_gracefully(sock),
                   fd=sock.fileno())

    def fileno(self) -> int:
        """The descriptor, for ``select`` (-1 if the link was built without one)."""
        return self._fd

    def read_available(self) -> bytes:
        """What was received so far, up to :data:`READ_LIMIT` bytes (b"" if nothing).

        Raises:
            LinkClosedError: the peer closed the stream, or it failed.
        """
        self._check_open()
        chunks: list[bytes] = []
        size = 0
        while size < READ_LIMIT:
            try:
                chunk = self._recv(min(_READ_CHUNK, READ_LIMIT - size))
            except BlockingIOError:
                break
            except OSError as e:
                raise LinkClosedError(self.where, f"read failed: {e.strerror or e}") from None
            if not chunk:
                if chunks:
                    break  # deliver these now; the next call reports the end
                raise LinkClosedError(self.where, "closed by the peer")
            chunks.append(chunk)
            size += len(chunk)
        return b"".join(chunks)

    def write(self, data: bytes) -> None:
        """Send ``data``; what the kernel cannot take now is dropped (counted).

        Raises:
            LinkClosedError: the peer is gone or the stream failed.
        """
        self._check_open()
        try:
            sent = self._send(data) if data else 0
        except BlockingIOError:
            sent = 0
        except OSError as e:
            raise LinkClosedError(self.where, f"write failed: {e.strerror or e}") from None
        self.dropped_bytes += len(data) - sent

    def close(self) -> None:
        """Release the descriptor; idempotent."""
        if not self._closed:
            self._closed = True
            self._release()

    def _check_open(self) -> None:
        if self._closed:
            raise LinkClosedError(self.where, "the link was closed here")


def _close_gracefully(sock: socket.socket) -> None:
    """Close a connected socket so that the peer reads everything written before the end.

    Closing a socket with unread input makes Linux send RST, and a peer that receives
    RST drops what it had not read yet: the last bytes sent (ARIA's CLOSE, a MAVLink
    farewell) would be lost. So: FIN after the data (``SHUT_WR``), the input read and
    dropped, then close.
    """
    try:
        sock.shutdown(socket.SHUT_WR)
        while sock.recv(_READ_CHUNK):
            pass
    except OSError:
        pass  # nothing more to read now (BlockingIOError), or the peer is gone
    sock.close()


def fd_io(fd: int) -> tuple[Callable[[int], bytes], Callable[[bytes], int]]:
    """recv and send on file descriptor ``fd``."""
    return (lambda n: os.read(fd, n)), (lambda b: os.write(fd, b))


class TcpListener:
    """A listening TCP socket; clients come out of :meth:`accept` as links.

    Args:
        host: address to bind (``127.0.0.1``: this machine only; ``0.0.0.0``: every
            interface).
        port: TCP port; 0 picks a free one (see :attr:`port`). ARIA's default is 8101.

    Raises:
        TransportError: the address cannot be bound (in use, not local, bad name).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8101) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # restart past TIME_WAIT
            sock.bind((host, port))
            sock.listen(4)
        except OSError as e:
            sock.close()
            where = f"tcp:{host}:{port}"
            raise TransportError(where, f"cannot listen: {e.strerror or e}") from None
        sock.setblocking(False)
        self._sock = sock
        self.host = host

    @property
    def port(self) -> int:
        """The port it listens on (the real one when created with port 0)."""
        return int(self._sock.getsockname()[1])

    def accept(self) -> StreamLink | None:
        """The next waiting client as a link, or None if none is waiting."""
        try:
            conn, (address, port) = self._sock.accept()
        except (BlockingIOError, InterruptedError):
            return None
        return StreamLink.from_socket(conn, f"tcp:{address}:{port}")

    def fileno(self) -> int:
        """The listening socket, for ``select`` (readable when a client waits)."""
        return self._sock.fileno()

    def close(self) -> None:
        """Stop listening; idempotent."""
        self._sock.close()


def connect_tcp(where: str, host: str, port: int,
                timeout_s: float = CONNECT_TIMEOUT_S) -> StreamLink:
    """A link on a new TCP connection to ``host``:``port`` (IPv4).

    Args:
        where: the address as the user gave it, for messages.
        host: a host name or IPv4 address.
        port: the TCP port, 1..65535.
        timeout_s: give up when the host has not answered in this long, s.

    Raises:
        TransportError: the host does not resolve, refuses the connection, is
            unreachable or does not answer within ``timeout_s`` (one line naming ``where``).
    """
    address = resolve_ipv4(where, host, port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.settimeout(timeout_s)
    try:
        sock.connect(address)
    except TimeoutError:
        sock.close()
        raise TransportError(where, f"no answer from {address[0]}:{address[1]} within "
                                    f"{timeout_s:g} s (host down or unreachable?)") from None
    except OSError as e:
        sock.close()
        raise TransportError(where, f"cannot connect to {address[0]}:{address[1]}: "
                                    f"{e.strerror or e}") from None
    return StreamLink.from_socket(sock, where)
