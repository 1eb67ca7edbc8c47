"""StreamPort: a MAVLink link's byte stream (serial, TCP client, TCP server), one peer at a time.

The stream side of ``--mavlink`` (the robot, ``robot.vehicle.stream_vehicle``) and
``--connect`` (the ground station, ``ground.station``), for the addresses
``serial:DEVICE[:BAUD]``, ``pty:PATH``, ``tcp:HOST:PORT`` and ``tcpin:HOST:PORT``
(``shared.link_address``). UDP is ``shared.udp_link``.

Rules:

1. One resource at a time: the serial port, the TCP connection, or (``tcpin``) the
   listening socket plus the one connection accepted on it. :meth:`StreamPort.open`
   binds a listener at once (a port in use is an error there); it opens nothing else.
2. :meth:`StreamPort.connect` opens the stream when there is none: the serial port
   (:class:`~shared.serial_port.SerialLink`), a TCP connection
   (:func:`~shared.stream_link.connect_tcp`, short timeout), or the next peer waiting on
   the listener (none waiting: False, at once). Failures raise
   :class:`~shared.errors.TransportError` in one line; the owner decides whether that
   ends it (the ground station) or is retried (the robot).
3. Loss: :meth:`read` and :meth:`write` raise :class:`~shared.byte_link.LinkClosedError`
   when the stream is gone (peer closed, device unplugged) and drop it first; the next
   :meth:`connect` starts again. A listener stays open throughout.
4. ``tcpin`` takes one peer at a time: :meth:`newcomer` returns a peer that connected
   meanwhile, and the owner keeps it (:meth:`replace`) or closes it; the protocol has
   no way to share the robot between two stations on one stream.
5. Not the network: a serial device or pty is a wire (``shared.link_security`` treats
   it so); bytes the kernel cannot take at once are dropped (``shared.stream_link``):
   MAVLink resyncs on the next packet.
"""

from __future__ import annotations

from shared.byte_link import ByteLink, LinkClosedError
from shared.link_address import LinkAddress, Scheme
from shared.serial_port import SerialLink
from shared.stream_link import CONNECT_TIMEOUT_S, TcpListener, connect_tcp

__all__ = ["MAVLINK_BAUD", "StreamPort"]

#: The serial rate when the address gives none, baud: SiK telemetry radios' default.
MAVLINK_BAUD = 57600


class StreamPort:
    """The stream of one link address (module rules). Use :meth:`open`.

    Args:
        address: a stream address (``tcp``, ``tcpin``, ``serial``, ``pty``).
        listener: the bound listener of a ``tcpin`` address, else None.
        baud: the serial rate when the address gives none, baud.
        connect_timeout_s: how long a TCP connect waits for an answer, s.
    """

    def __init__(self, address: LinkAddress, listener: TcpListener | None, baud: int,
                 connect_timeout_s: float) -> None:
        self.address = address
        self._listener = listener
        self._baud = baud
        self._connect_timeout_s = connect_timeout_s
        self._link: ByteLink | None = None
        self.url = address.text if listener is None else (
            f"tcpin:{address.host}:{listener.port}")
        """The address, with the port a ``tcpin:HOST:0`` listener got."""

    @classmethod
    def open(cls, address: LinkAddress, baud: int = MAVLINK_BAUD,
             connect_timeout_s: float = CONNECT_TIMEOUT_S) -> StreamPort:
        """A port for ``address``; a ``tcpin`` listener is bound now (rule 1).

        Raises:
            TransportError: the listener cannot be bound (in use, not a local address).
            ValueError: ``address`` is UDP.
        """
        if not address.stream:
            raise ValueError(f"{address.text} is not a stream address")
        listener = None
        if address.scheme is Scheme.TCPIN:
            listener = TcpListener(address.host, address.port)
        return cls(address, listener, baud, connect_timeout_s)

    @property
    def connected(self) -> bool:
        """A stream is open."""
        return self._link is not None

    @property
    def local_port(self) -> int | None:
        """The port a ``tcpin`` listener is bound to; None for other addresses."""
        return None if self._listener is None else self._listener.port

    def connect(self) -> bool:
        """Open the stream if there is none (rule 2).

        Returns:
            Whether a stream is open now (False: no peer waiting on the listener yet).

        Raises:
            TransportError: the device or host cannot be opened or reached (one line).
        """
        if self._link is not None:
            return True
        address = self.address
        if self._listener is not None:
            self._link = self._listener.accept()
        elif address.scheme is Scheme.TCP:
            self._link = connect_tcp(address.text, address.host, address.port,
                                     self._connect_timeout_s)
        else:
            baud = address.baud if address.baud is not None else self._baud
            self._link = SerialLink.open(address.device, baud)
        return self._link is not None

    def newcomer(self) -> ByteLink | None:
        """A peer that connected to the listener while another is served (rule 4)."""
        return self._listener.accept() if self._listener is not None else None

    def replace(self, link: ByteLink) -> None:
        """Serve ``link`` (a :meth:`newcomer`) from now on; the old peer is closed."""
        self.drop()
        self._link = link

    def read(self) -> bytes:
        """What arrived (b"" if nothing or no stream).

        Raises:
            LinkClosedError: the stream is gone (and dropped: rule 3).
        """
        if self._link is None:
            return b""
        try:
            return self._link.read_available()
        except LinkClosedError:
            self.drop()
            raise

    def write(self, data: bytes) -> bool:
        """Send ``data`` on the stream.

        Returns:
            False if there is no stream (nothing sent).

        Raises:
            LinkClosedError: the stream is gone (and dropped: rule 3).
        """
        if self._link is None:
            return False
        try:
            self._link.write(data)
        except LinkClosedError:
            self.drop()
            raise
        return True

    def fileno(self) -> int:
        """What to ``select`` on for input: the stream, else the listener; -1 if neither."""
        link = self._link
        if link is not None:
            fileno = getattr(link, "fileno", None)
            return int(fileno()) if fileno is not None else -1
        return self._listener.fileno() if self._listener is not None else -1

    def drop(self) -> None:
        """Close the stream, if any (a listener stays)."""
        link, self._link = self._link, None
        if link is not None:
            link.close()

    def close(self) -> None:
        """Close the stream and the listener; idempotent."""
        self.drop()
        if self._listener is not None:
            self._listener.close()

    def __enter__(self) -> StreamPort:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
