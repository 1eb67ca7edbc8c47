"""StreamVehicle: a :class:`~robot.vehicle.endpoint.VehicleEndpoint` on a byte stream.

``--mavlink serial:DEVICE[:BAUD]`` (a SiK telemetry radio), ``pty:PATH``,
``tcp:HOST:PORT`` (the robot calls a ground station) and ``tcpin:HOST:PORT`` (ground
stations call the robot, one at a time), through :class:`~shared.stream_port.StreamPort`.
Threads, taps, reject reports and errors are :class:`~robot.vehicle.vehicle_io.VehicleIo`'s
(its rules); UDP is ``udp_vehicle``'s.

Rules:

1. One round: (re)connect when due (rule 3), the stream read into the endpoint as a
   chunk of a byte stream (packets may span chunks), then every packet of
   ``endpoint.poll`` written. ``poll`` runs whether a stream is open or not, so the
   endpoint's timers and its GCS failsafe go on; what it gives while no stream is open
   is dropped, as a radio out of range drops it. The taps get each verified packet
   received, whole, and each packet written (``VehicleIo`` rule 2); the packets that
   decoded unverified or not at all count as rejected.
2. The robot keeps running whatever the link does: a peer that closes, a device
   unplugged or a connect that fails is logged (one WARNING line per outage), the
   stream dropped, and the connect retried every :data:`RETRY_NS` (a listener takes
   the next station at once); meanwhile the
   endpoint's GCS failsafe acts as on any silence. A ground station that comes back is
   served again: the serial device re-opened, the TCP connection made again, or the
   next peer accepted on the listener.
3. ``tcpin`` serves one ground station at a time (``StreamPort`` rule 4). A newcomer
   replaces the peer served when that peer has sent no verified message for the GCS
   timeout (``MavlinkConfig.gcs_timeout_ns``: a station that died without closing its
   connection); otherwise the newcomer is closed at once. On an unsigned link whoever
   connects first drives the robot: the entry points keep unsigned listeners on
   loopback (``shared.link_security``).
"""

from __future__ import annotations

import logging

from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.vehicle_io import VehicleIo
from shared.byte_link import LinkClosedError
from shared.clock import NS_PER_S, Clock
from shared.errors import TransportError
from shared.stream_port import StreamPort

__all__ = ["RETRY_NS", "StreamVehicle"]

logger = logging.getLogger(__name__)

#: How often a lost or failed stream is tried again, ns (rule 2).
RETRY_NS = NS_PER_S


class StreamVehicle(VehicleIo):
    """The vehicle's I/O on a serial or TCP stream (module rules).

    Args:
        endpoint: the vehicle; the adapter owns it from now on (closing closes it).
        port: the stream's port (opened: a ``tcpin`` listener bound); the adapter owns it.
        clock: time for the I/O thread.
    """

    def __init__(self, endpoint: VehicleEndpoint, port: StreamPort, clock: Clock) -> None:
        super().__init__(endpoint, port, clock)
        self.link: StreamPort = port
        self._retry_ns: int | None = None  # when to try to connect next; None: now
        self._outage: str | None = None  # the failure logged for the current outage
        self._heard_ns: int | None = None  # the last verified message of the peer served

    def _exchange(self, now_ns: int) -> None:
        """Connect when due, stream in, packets out (rules 1 to 3)."""
        port = self.link
        try:
            self._connect(now_ns)
            if port.connected:
                data = port.read()  # first: a peer that left is seen before a newcomer
                if data:
                    self._receive(data, now_ns)
                self._take_newcomer(now_ns)
            for packet in self.endpoint.poll(now_ns):
                if port.write(packet):
                    self._tap("out", packet, now_ns)
        except LinkClosedError as e:
            self._lost(str(e), now_ns)

    def _connect(self, now_ns: int) -> None:
        if self.link.connected or (self._retry_ns is not None and now_ns < self._retry_ns):
            return
        try:
            if self.link.connect():
                logger.info("vehicle: ground link %s connected", self.link.url)
                self._outage, self._retry_ns, self._heard_ns = None, None, now_ns
        except TransportError as e:
            self._lost(str(e), now_ns)

    def _take_newcomer(self, now_ns: int) -> None:
        """Rule 3: a newcomer replaces a silent peer, or is turned away."""
        newcomer = self.link.newcomer()
        if newcomer is None:
            return
        silent = self._heard_ns is None or (
            now_ns - self._heard_ns >= self.endpoint.config.mavlink.gcs_timeout_ns)
        if silent:
            logger.warning("vehicle: ground link %s: a new station replaces the silent one",
                           self.link.url)
            self.link.replace(newcomer)
            self._heard_ns = now_ns
        else:
            logger.warning("vehicle: ground link %s: another station refused (one at a time)",
                           self.link.url)
            newcomer.close()

    def _receive(self, data: bytes, now_ns: int) -> None:
        bad = self.endpoint.codec.bad_packets
        verified: list[bytes] = []
        messages = self.endpoint.receive(data, now_ns, verified=verified)
        self.unverified += self.endpoint.codec.bad_packets - bad + messages - len(verified)
        for packet in verified:
            self._tap("in", packet, now_ns)
        if verified:
            self._heard_ns = now_ns

    def _lost(self, problem: str, now_ns: int) -> None:
        """Rule 2: one line per outage, then retries."""
        self.link.drop()
        listening = self.link.local_port is not None
        if self._outage is None:
            then = ("waiting for the next ground station" if listening
                    else f"trying again every {RETRY_NS / NS_PER_S:.0f} s")
            logger.warning("vehicle: ground link lost: %s; %s", problem, then)
        self._outage = problem
        # A listener takes the next station at once; a device or host is retried later.
        self._retry_ns = None if listening else now_ns + RETRY_NS
