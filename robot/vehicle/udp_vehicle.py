"""UdpVehicle: a :class:`~robot.vehicle.endpoint.VehicleEndpoint` on a UDP socket.

Threads, taps, reject reports and errors are :class:`~robot.vehicle.vehicle_io.VehicleIo`'s
(its rules); serial and TCP links are ``stream_vehicle``'s.

Rules:

1. :meth:`UdpVehicle.service` does one round of I/O at ``now_ns``: the socket drained
   (:meth:`~shared.udp_link.UdpLink.drain`), the datagrams into the endpoint (each
   parsed on its own: garbage in one cannot swallow the packets of the next), then
   every packet of ``endpoint.poll`` out, one datagram each (``VehicleIo`` rule 1).
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

from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.vehicle_io import REJECT_REPORT_PERIOD_NS, Rejected, VehicleIo
from shared.clock import Clock
from shared.udp_link import Peer, UdpLink

__all__ = ["REJECT_REPORT_PERIOD_NS", "STRANGER_BUDGET", "Rejected", "UdpVehicle"]

#: Datagrams from anyone but the trusted peer handled per round at most (rule 5).
STRANGER_BUDGET = 16


class UdpVehicle(VehicleIo):
    """The vehicle's UDP I/O (module rules).

    Args:
        endpoint: the vehicle; the adapter owns it from now on (closing closes it).
        link: the socket; the adapter owns it.
        clock: time for the I/O thread.
    """

    def __init__(self, endpoint: VehicleEndpoint, link: UdpLink, clock: Clock) -> None:
        super().__init__(endpoint, link, clock)
        self.link: UdpLink = link
        self._reply_to: Peer | None = link.peer

    @classmethod
    def open(cls, url: str, endpoint: VehicleEndpoint, clock: Clock) -> UdpVehicle:
        """The vehicle on a new :class:`UdpLink` for ``url`` (``udpin:0.0.0.0:14550``...).

        Raises:
            TransportError: a bad connection string or a port in use.
        """
        return cls(endpoint, UdpLink.open(url), clock)

    def _exchange(self, now_ns: int) -> None:
        """Datagrams in, packets out (rules 1 and 5)."""
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
            self._tap("in", data, now_ns)
            if self.link.listening:
                self._reply_to = sender
        self.link.peer = self._reply_to
        for packet in self.endpoint.poll(now_ns):
            self._tap("out", packet, now_ns)
            self.link.send(packet)
