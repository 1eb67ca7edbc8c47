"""UdpVehicle: a :class:`~robot.vehicle.endpoint.VehicleEndpoint` on a UDP socket.

Rules:

1. :meth:`UdpVehicle.service` does one round of I/O at ``now_ns``: every waiting
   datagram into the endpoint (each parsed on its own: garbage in one cannot swallow
   the packets of the next), then every packet of ``endpoint.poll`` out, one
   datagram each. Either the robot's loop calls it, or the vehicle's own thread
   (:meth:`start_thread`, every ``MavlinkConfig.service_period_ns`` on the injected
   clock); never both. The application's callbacks run in that thread.
2. A listening link (``udpin``) replies to the last sender whose datagram held a
   verified message (:meth:`~shared.mavlink.dialect.MavlinkCodec.is_verified`: of our
   dialect, so its CRC was checked, and on a signed link validly signed; the codec
   checks both while the endpoint parses, before the reply address is chosen and
   anything is sent). Corrupt packets and unknown message ids are counted
   (``codec.bad_packets``, ``codec.unknown_packets``) but never move the reply address.
   On a signed link that is the ground station that authenticated last: a stranger's
   unsigned datagram (even one the signing policy lets through), a wrongly signed one
   and a replay of the station's own packets from another socket (its timestamp is
   spent) all leave the replies and telemetry where they are. On an unsigned link any
   well-formed packet moves them, so whoever can reach the socket can take them: the
   entry points keep unsigned links on loopback (``shared.link_security``). A
   ``udpout`` link always sends to its peer.
3. Every datagram received and every packet sent goes to the ``packet_taps``
   (``tap(direction, data, now_ns)``, direction ``"in"`` or ``"out"``), in the I/O
   thread: the field log's MAVLink in and out.
4. Errors: a closed or failed socket raises
   :class:`~shared.byte_link.LinkClosedError` from :meth:`service`; the thread logs
   it and ends. Any other exception of a round (a bug in the endpoint or a tap) is
   recorded in the endpoint's :attr:`~robot.vehicle.endpoint.VehicleEndpoint.faults`
   (counted in SYS_STATUS, logged once per kind), the rest of the round is dropped and
   the next round runs: the link outlives it, whether the thread or the robot's loop
   calls :meth:`service`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from robot.vehicle.endpoint import VehicleEndpoint
from shared.byte_link import LinkClosedError
from shared.clock import Clock, service_loop
from shared.errors import IllegalEventError
from shared.udp_link import Peer, UdpLink


class UdpVehicle:
    """The vehicle's UDP I/O (module rules).

    Args:
        endpoint: the vehicle; the adapter owns it from now on (closing closes it).
        link: the socket; the adapter owns it.
        clock: time for the I/O thread.
    """

    def __init__(self, endpoint: VehicleEndpoint, link: UdpLink, clock: Clock) -> None:
        self.endpoint = endpoint
        self.link = link
        self._clock = clock
        self._reply_to: Peer | None = link.peer
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._closed = False
        self.packet_taps: list[Callable[[str, bytes, int], None]] = []
        """Called with every datagram in and packet out (rule 3)."""

    @classmethod
    def open(cls, url: str, endpoint: VehicleEndpoint, clock: Clock) -> UdpVehicle:
        """The vehicle on a new :class:`UdpLink` for ``url`` (``udpin:0.0.0.0:14550``...).

        Raises:
            TransportError: a bad connection string or a port in use.
        """
        return cls(endpoint, UdpLink.open(url), clock)

    def service(self, now_ns: int) -> None:
        """One round of I/O at ``now_ns`` (rules 1 and 4).

        Raises:
            LinkClosedError: the socket is closed or failed.
        """
        try:
            self._exchange(now_ns)
        except LinkClosedError:
            raise
        except Exception as e:  # a bug; it must not end the link (rule 4)
            self.endpoint.faults.record("I/O round", e)

    def _exchange(self, now_ns: int) -> None:
        """Datagrams in, packets out (rule 1)."""
        with self._lock:
            if self._closed:
                return
            codec = self.endpoint.codec
            for data, sender in self.link.receive():
                for tap in self.packet_taps:
                    tap("in", data, now_ns)
                verified = codec.verified_packets
                self.endpoint.receive(data, now_ns, datagram=True)
                if codec.verified_packets > verified and self.link.listening:
                    self._reply_to = sender
            self.link.peer = self._reply_to
            for packet in self.endpoint.poll(now_ns):
                for tap in self.packet_taps:
                    tap("out", packet, now_ns)
                self.link.send(packet)

    def start_thread(self) -> None:
        """Service the link from a daemon thread; idempotent.

        Raises:
            IllegalEventError: the vehicle is closed.
        """
        with self._lock:
            if self._closed:
                raise IllegalEventError("UdpVehicle", "CLOSED", "start_thread")
            if self._thread is None:
                self._thread = threading.Thread(
                    target=service_loop, name="mavlink-io", daemon=True,
                    args=(self.service, self._clock, self.endpoint.config.mavlink.service_period_ns,
                          self._stop, "vehicle"))
                self._thread.start()

    def close(self) -> None:
        """Stop the thread, close the endpoint and the socket; idempotent."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join()
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self.endpoint.close()
            self.link.close()

    def __enter__(self) -> UdpVehicle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
