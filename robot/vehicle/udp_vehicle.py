"""UdpVehicle: a :class:`~robot.vehicle.endpoint.VehicleEndpoint` on a UDP socket.

Rules:

1. :meth:`UdpVehicle.service` does one round of I/O at ``now_ns``: the socket drained
   (:meth:`~shared.udp_link.UdpLink.drain`), the datagrams into the endpoint (each
   parsed on its own: garbage in one cannot swallow the packets of the next), then
   every packet of ``endpoint.poll`` out, one datagram each. Either the robot's loop
   calls it, or the vehicle's own thread (:meth:`start_thread`, every
   ``MavlinkConfig.service_period_ns`` on the injected clock); never both. The
   application's callbacks run in that thread.
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
3. Every datagram received that held a verified message and every packet sent goes
   to the ``packet_taps`` (``tap(direction, data, now_ns)``, direction ``"in"`` or
   ``"out"``), in the I/O thread: the field log's MAVLink in and out. Rejected
   datagrams (nothing verified in them: corrupt, unknown ids, unsigned or wrongly
   signed) and shed ones are only counted: the ``reject_observers`` get the counts
   (:class:`Rejected`) of each :data:`REJECT_REPORT_PERIOD_NS` that had any, so an
   outsider cannot fill the log.
4. Errors: a closed or failed socket raises
   :class:`~shared.byte_link.LinkClosedError` from :meth:`service`; the thread logs
   it and ends. Any other exception of a round (a bug in the endpoint or a tap) is
   recorded in the endpoint's :attr:`~robot.vehicle.endpoint.VehicleEndpoint.faults`
   (counted in SYS_STATUS, logged once per kind), the rest of the round is dropped and
   the next round runs: the link outlives it, whether the thread or the robot's loop
   calls :meth:`service`.
5. Floods: the peer the vehicle answers (rule 2; a ``udpout`` link's fixed peer) is
   trusted: all its datagrams are handled, first. Of everyone else's, at most
   :data:`STRANGER_BUDGET` per round are handled; the rest are read and dropped
   unparsed (:attr:`UdpVehicle.shed`, also in SYS_STATUS ``errors_comm``), so that
   however fast strangers send, the socket is emptied each round (up to
   ``DRAIN_LIMIT`` datagrams), the trusted station's datagrams are not lost in a full
   buffer, and the round ends with its sending: heartbeats and telemetry go out on
   time. A new ground station is a stranger until its first verified message; under a
   flood it competes for the budget.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

from robot.vehicle.endpoint import VehicleEndpoint
from shared.byte_link import LinkClosedError
from shared.clock import NS_PER_S, Clock, service_loop
from shared.errors import IllegalEventError
from shared.udp_link import Peer, UdpLink

#: Datagrams from anyone but the trusted peer handled per round at most (rule 5).
STRANGER_BUDGET = 16
#: Rejected traffic is reported at most this often, ns (rule 3).
REJECT_REPORT_PERIOD_NS = 10 * NS_PER_S


@dataclass(frozen=True, slots=True)
class Rejected:
    """Datagrams received and not accepted over a report period (rule 3).

    Attributes:
        unverified: handled, but held no verified message (corrupt, unknown message ids,
            unsigned or wrongly signed on a signed link).
        shed: from strangers past the round's budget: read and dropped unparsed.
        period_ns: the time they came in, ns (from the previous report, or the first round).
    """

    unverified: int
    shed: int
    period_ns: int


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
        """Called with every accepted datagram in and packet out (rule 3)."""
        self.reject_observers: list[Callable[[Rejected, int], None]] = []
        """Called with the rejected traffic of a period and the time, ns (rule 3)."""
        self.unverified = 0
        """Datagrams handled that held no verified message so far (rule 3)."""
        self._reported = (0, 0)  # (unverified, shed) at the last report
        self._report_ns: int | None = None

    @property
    def shed(self) -> int:
        """Datagrams from strangers dropped unparsed so far (rule 5)."""
        return self.endpoint.shed_datagrams

    @classmethod
    def open(cls, url: str, endpoint: VehicleEndpoint, clock: Clock) -> UdpVehicle:
        """The vehicle on a new :class:`UdpLink` for ``url`` (``udpin:0.0.0.0:14550``...).

        Raises:
            TransportError: a bad connection string or a port in use.
        """
        return cls(endpoint, UdpLink.open(url), clock)

    def service(self, now_ns: int) -> None:
        """One round of I/O at ``now_ns`` (rules 1, 4 and 5).

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
        """Datagrams in, packets out (rules 1 and 5)."""
        with self._lock:
            if self._closed:
                return
            codec = self.endpoint.codec
            trusted = () if self._reply_to is None else (self._reply_to,)
            drained = self.link.drain(trusted, STRANGER_BUDGET)
            self.endpoint.shed_datagrams += drained.shed
            for data, sender in drained.trusted + drained.others:
                verified = codec.verified_packets
                self.endpoint.receive(data, now_ns, datagram=True)
                if codec.verified_packets == verified:
                    self.unverified += 1
                    continue
                for tap in self.packet_taps:
                    tap("in", data, now_ns)
                if self.link.listening:
                    self._reply_to = sender
            self.link.peer = self._reply_to
            for packet in self.endpoint.poll(now_ns):
                for tap in self.packet_taps:
                    tap("out", packet, now_ns)
                self.link.send(packet)
            self._report_rejects(now_ns)

    def _report_rejects(self, now_ns: int) -> None:
        """Rule 3: the counts of the period, once it is over and if it had any."""
        if self._report_ns is None:
            self._report_ns = now_ns
        if now_ns - self._report_ns < REJECT_REPORT_PERIOD_NS:
            return
        unverified, shed = self.unverified - self._reported[0], self.shed - self._reported[1]
        if unverified or shed:
            rejected = Rejected(unverified, shed, now_ns - self._report_ns)
            for observer in self.reject_observers:
                observer(rejected, now_ns)
        self._reported, self._report_ns = (self.unverified, self.shed), now_ns

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
