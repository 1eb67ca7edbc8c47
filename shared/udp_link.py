"""UdpLink: MAVLink datagrams over UDP, opened from a pymavlink-style connection string.

Connection strings (pymavlink ``mavutil.mavlink_connection`` spells them the same):

=====================  ===================================================================
``udpin:HOST:PORT``    listen on HOST:PORT (``0.0.0.0`` for every interface; port 0 picks
                       a free one, see :attr:`UdpLink.local_port`); send to the last peer a
                       datagram came from, so nothing goes out before the first one arrives
``udp:HOST:PORT``      the same as ``udpin`` (pymavlink's alias)
``udpout:HOST:PORT``   send to HOST:PORT from a free local port (on loopback when HOST is
                       a loopback address, else on every interface); receive from anyone
                       who can reach that port
=====================  ===================================================================

The strings are parsed by ``shared.link_address`` (the syntax of every link);
``shared.link_security.reaches_network`` tells whether a link is open to the network
(the entry points refuse that unsigned unless asked).

Theory of operation: one datagram carries one or more whole MAVLink packets; the
link never splits or joins them. ``send``, ``receive`` and ``drain`` never block. UDP loses
datagrams by nature, so a send that the kernel refuses (no route, buffer full) is
counted in :attr:`UdpLink.send_errors` and dropped like a lost datagram; only a
closed socket raises. Bad connection strings, unresolvable hosts and ports in use
raise :class:`~shared.errors.TransportError` with one line naming the string (the entry
points parse it first, for a message naming their option).
IPv4 only, like pymavlink's UDP links.

Floods: the socket asks for a :data:`RECEIVE_BUFFER_BYTES` receive buffer (the kernel
caps it at ``net.core.rmem_max``, doubled), and :meth:`UdpLink.drain` empties it
each round, up to :data:`DRAIN_LIMIT` datagrams, copying only what its owner will
handle: every datagram from the peers it trusts, and at most a budget of the others;
the rest are read and dropped uncopied (counted), so a flood from strangers cannot
fill the buffer that the trusted peer's datagrams wait in, nor keep the owner from
sending.
"""

from __future__ import annotations

import enum
import socket
from collections.abc import Collection
from dataclasses import dataclass, field

from shared.byte_link import LinkClosedError
from shared.errors import InputError, TransportError
from shared.ipv4 import Peer, is_loopback, resolve_ipv4
from shared.link_address import Scheme, parse_link_address

__all__ = ["Drained", "Peer", "UdpLink", "UdpMode", "parse_udp_url"]

#: Largest UDP payload, bytes.
MAX_DATAGRAM = 65535
#: Most datagrams one :meth:`UdpLink.receive` returns, so one busy peer cannot starve a loop.
MAX_BATCH = 256
#: Receive buffer asked for, bytes (about 10,000 small datagrams at the kernel's
#: per-datagram overhead; Linux grants at most twice ``net.core.rmem_max``).
RECEIVE_BUFFER_BYTES = 8 * 1024 * 1024
#: Most datagrams one :meth:`UdpLink.drain` reads (about 20 ms of ``recvfrom`` on a loaded
#: core), so a round of its owner ends and sends whatever comes in.
DRAIN_LIMIT = 4096


class UdpMode(enum.Enum):
    """Which end of the conversation the link is."""

    IN = "udpin"  #: listens; replies to the last sender
    OUT = "udpout"  #: sends to a fixed peer


def parse_udp_url(url: str) -> tuple[UdpMode, str, int]:
    """Split a connection string into (mode, host, port) (``shared.link_address``).

    Raises:
        TransportError: not one of the three forms, or a bad host or port (one line
            naming ``url``).
    """
    try:
        address = parse_link_address(url, url, (Scheme.UDPIN, Scheme.UDPOUT))
    except InputError as e:
        raise TransportError(url, e.problem) from None
    mode = UdpMode.IN if address.scheme is Scheme.UDPIN else UdpMode.OUT
    return mode, address.host, address.port


def _bind_address(mode: UdpMode, address: Peer) -> Peer:
    """Where a link's socket is bound: the listening address, or for ``udpout`` a free port
    on loopback (a loopback peer) or on every interface."""
    if mode is UdpMode.IN:
        return address
    return ("127.0.0.1" if is_loopback(address[0]) else "0.0.0.0", 0)


@dataclass(slots=True)
class Drained:
    """What one :meth:`UdpLink.drain` read.

    Attributes:
        trusted: ``(data, sender)`` of every datagram from a trusted peer, in arrival order.
        others: ``(data, sender)`` of the first datagrams from anyone else, at most the
            budget, in arrival order.
        shed: datagrams from others read past the budget and dropped.
    """

    trusted: list[tuple[bytes, Peer]] = field(default_factory=list)
    others: list[tuple[bytes, Peer]] = field(default_factory=list)
    shed: int = 0


class UdpLink:
    """A non-blocking UDP socket that carries MAVLink datagrams (module docstring).

    Use :meth:`open`; the constructor takes an already bound socket.

    Args:
        sock: a bound, non-blocking IPv4 UDP socket; the link owns it.
        url: the connection string, for messages.
        mode: listening or sending end.
        peer: where :meth:`send` goes (None until a datagram arrives, for ``udpin``).
    """

    def __init__(self, sock: socket.socket, url: str, mode: UdpMode, peer: Peer | None) -> None:
        self._sock = sock
        self.url = url
        self.mode = mode
        self.peer = peer
        """Where :meth:`send` goes; a ``udpin`` link moves it to each datagram's sender.
        The owner may set it (e.g. back to the last sender it trusts)."""
        self.local_port: int = sock.getsockname()[1]
        """The port the socket is bound to (the one picked when opened with port 0)."""
        self.send_errors = 0
        """Datagrams the kernel refused to send (dropped)."""
        self._closed = False
        self._scratch = bytearray(MAX_DATAGRAM)
        self._view = memoryview(self._scratch)

    @property
    def receive_buffer_bytes(self) -> int:
        """The socket's receive buffer as the kernel granted it, bytes."""
        return self._sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)

    @classmethod
    def open(cls, url: str) -> UdpLink:
        """Open ``url`` (see the module docstring for the forms).

        Raises:
            TransportError: a bad string, an unknown host, or a port in use (one line
                naming ``url``).
        """
        mode, host, port = parse_udp_url(url)
        address = resolve_ipv4(url, host, port)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
            sock.bind(_bind_address(mode, address))
            sock.setblocking(False)
        except OSError as e:
            sock.close()
            raise TransportError(url, f"cannot bind {address[0]}:{address[1]}: "
                                      f"{e.strerror or e}") from None
        return cls(sock, url, mode, None if mode is UdpMode.IN else address)

    @property
    def listening(self) -> bool:
        """A ``udpin`` link (it follows the last sender)."""
        return self.mode is UdpMode.IN

    def fileno(self) -> int:
        """The socket's descriptor, for ``select``."""
        return self._sock.fileno()

    def send(self, data: bytes) -> bool:
        """Send ``data`` as one datagram to :attr:`peer`.

        Returns:
            True if handed to the kernel; False if there is no peer yet (``udpin``
            before the first datagram) or the kernel refused it (counted).

        Raises:
            LinkClosedError: the link was closed.
        """
        self._check_open()
        if self.peer is None:
            return False
        try:
            self._sock.sendto(data, self.peer)
        except OSError:
            self.send_errors += 1
            return False
        return True

    def receive(self) -> list[tuple[bytes, Peer]]:
        """Every datagram waiting (at most :data:`MAX_BATCH`), without blocking.

        Returns:
            ``(data, sender)`` pairs in arrival order; a ``udpin`` link's :attr:`peer`
            becomes the last sender.

        Raises:
            LinkClosedError: the link was closed, or the socket failed.
        """
        self._check_open()
        out: list[tuple[bytes, Peer]] = []
        while len(out) < MAX_BATCH:
            try:
                data, sender = self._sock.recvfrom(MAX_DATAGRAM)
            except BlockingIOError:
                break
            except OSError as e:
                raise LinkClosedError(self.url, f"receive failed: {e.strerror or e}") from None
            out.append((data, (str(sender[0]), int(sender[1]))))
        if out and self.listening:
            self.peer = out[-1][1]
        return out

    def drain(self, trusted: Collection[Peer], budget: int,
              limit: int = DRAIN_LIMIT) -> Drained:
        """Read every datagram waiting (at most ``limit``), without blocking, keeping those
        of ``trusted`` peers and the first ``budget`` of the others (module docstring).

        Unlike :meth:`receive`, the link's :attr:`peer` does not move: the owner decides
        whom to answer.

        Raises:
            LinkClosedError: the link was closed, or the socket failed.
        """
        self._check_open()
        out = Drained()
        for _ in range(limit):
            try:
                size, sender = self._sock.recvfrom_into(self._scratch)
            except BlockingIOError:
                break
            except OSError as e:
                raise LinkClosedError(self.url, f"receive failed: {e.strerror or e}") from None
            if sender in trusted:  # an IPv4 (host, port) tuple, as Peer
                out.trusted.append((bytes(self._view[:size]), sender))
            elif len(out.others) < budget:
                out.others.append((bytes(self._view[:size]), sender))
            else:
                out.shed += 1
        return out

    def close(self) -> None:
        """Release the socket; idempotent."""
        self._closed = True
        self._sock.close()

    def _check_open(self) -> None:
        if self._closed:
            raise LinkClosedError(self.url, "the UDP link is closed")

    def __enter__(self) -> UdpLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
