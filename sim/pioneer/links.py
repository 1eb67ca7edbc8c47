"""Real byte links for the emulated Pioneer: a pseudo-terminal, TCP clients, a TCP listener.

The links are :class:`shared.byte_link.ByteLink` adapters, non-blocking, each owning
its file descriptor or socket. A write the kernel cannot take at once is dropped and
counted (``dropped_bytes``), as bytes are lost on a serial line nobody reads; the
client's deframer resyncs on the next packet. OS errors become
:class:`~shared.byte_link.LinkClosedError` (a link that went away) or
:class:`~shared.errors.TransportError` (one that cannot be opened).
"""

from __future__ import annotations

import os
import socket
import tty
from collections.abc import Callable
from pathlib import Path

from shared.byte_link import LinkClosedError
from shared.errors import TransportError

_READ_CHUNK = 4096
READ_LIMIT = 65536
"""Most bytes one :meth:`StreamLink.read_available` returns (the rest waits for the next
call): a client that sends without pause cannot hold a tick for ever. A serial line at
115200 baud carries about 11.5 kB/s."""


class StreamLink:
    """A :class:`~shared.byte_link.ByteLink` over a non-blocking OS stream.

    Build one with :meth:`from_fd` or :meth:`from_socket`.

    Args:
        where: the transport, for messages (``/dev/pts/3``, ``tcp:127.0.0.1:50312``).
        recv: reads up to n bytes; b"" at end of stream; raises BlockingIOError when empty.
        send: writes bytes, returns how many it took; raises BlockingIOError when full.
        release: closes the descriptor.
    """

    def __init__(
        self,
        where: str,
        recv: Callable[[int], bytes],
        send: Callable[[bytes], int],
        release: Callable[[], None],
    ) -> None:
        self.where = where
        self.dropped_bytes = 0
        """Bytes written while the kernel's buffer was full, and so lost."""
        self._recv, self._send, self._release = recv, send, release
        self._closed = False

    @classmethod
    def from_fd(cls, fd: int, where: str) -> StreamLink:
        """A link owning file descriptor ``fd`` (made non-blocking)."""
        os.set_blocking(fd, False)
        return cls(where, *_fd_io(fd), release=lambda: os.close(fd))

    @classmethod
    def from_socket(cls, sock: socket.socket, where: str) -> StreamLink:
        """A link owning connected stream socket ``sock`` (made non-blocking, no Nagle delay)."""
        sock.setblocking(False)
        if sock.family in (socket.AF_INET, socket.AF_INET6):
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return cls(where, sock.recv, sock.send, sock.close)

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


def _fd_io(fd: int) -> tuple[Callable[[int], bytes], Callable[[bytes], int]]:
    """recv and send on file descriptor ``fd``."""
    return (lambda n: os.read(fd, n)), (lambda b: os.write(fd, b))


class PtyLink(StreamLink):
    """The master end of a new pseudo-terminal; a client opens :attr:`path` as its serial port.

    The slave end stays open here too, so the terminal survives between clients and
    the master never reads end-of-file; it is put in raw mode (no echo, no line
    editing, no CR/LF translation), so bytes pass as they are.

    Args:
        symlink: also point this symbolic link at the slave (e.g. ``/tmp/vmnav-pioneer``);
            an existing symlink there is replaced, and the link is removed on close.

    Raises:
        TransportError: no pty can be opened, or the symlink cannot be made.
    """

    def __init__(self, symlink: Path | None = None) -> None:
        try:
            master, slave = os.openpty()
        except OSError as e:
            raise TransportError("pty", f"cannot open a pseudo-terminal: {e.strerror}") from None
        tty.setraw(slave)
        os.set_blocking(master, False)
        self._master, self._slave = master, slave
        self.path = os.ttyname(slave)
        """The slave's device path, for the client."""
        self.symlink = symlink
        super().__init__(self.path, *_fd_io(master), release=self._release_pty)
        if symlink is not None:
            try:
                if symlink.is_symlink():
                    symlink.unlink()
                symlink.symlink_to(self.path)
            except OSError as e:
                self.symlink = None
                self.close()
                raise TransportError(symlink, f"cannot link to {self.path}: {e.strerror}") from None

    def _release_pty(self) -> None:
        os.close(self._master)
        os.close(self._slave)
        if self.symlink is not None:
            self.symlink.unlink(missing_ok=True)


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

    def close(self) -> None:
        """Stop listening; idempotent."""
        self._sock.close()
