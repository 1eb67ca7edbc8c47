"""VehicleIo: what the vehicle's transport adapters share (UDP: ``udp_vehicle``; serial and
TCP: ``stream_vehicle``).

Rules (each adapter's own rules say what one round does):

1. :meth:`VehicleIo.service` does one round of I/O at ``now_ns``. Either the robot's
   loop calls it, or the vehicle's own thread (:meth:`start_thread`, every
   ``MavlinkConfig.service_period_ns`` on the injected clock); never both. The
   application's callbacks run in that thread.
2. Every packet received that held a verified message and every packet sent goes to the
   ``packet_taps`` (``tap(direction, data, now_ns)``, direction ``"in"`` or ``"out"``),
   in the I/O thread: the field log's MAVLink in and out. Rejected input is only
   counted: the ``reject_observers`` get the counts (:class:`Rejected`) of each
   :data:`REJECT_REPORT_PERIOD_NS` that had any, so an outsider cannot fill the log.
3. Errors: a closed or failed transport the adapter cannot recover from raises
   :class:`~shared.byte_link.LinkClosedError` from :meth:`service`; the thread logs it
   and ends. Any other exception of a round (a bug in the endpoint or a tap) is
   recorded in the endpoint's :attr:`~robot.vehicle.endpoint.VehicleEndpoint.faults`
   (counted in SYS_STATUS, logged once per kind), the rest of the round is dropped and
   the next round runs.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from robot.vehicle.endpoint import VehicleEndpoint
from shared.byte_link import LinkClosedError
from shared.clock import NS_PER_S, Clock, service_loop
from shared.errors import IllegalEventError

#: Rejected traffic is reported at most this often, ns (rule 2).
REJECT_REPORT_PERIOD_NS = 10 * NS_PER_S


class Closable(Protocol):
    """The transport an adapter owns."""

    def close(self) -> None:
        """Release it; idempotent."""
        ...


@dataclass(frozen=True, slots=True)
class Rejected:
    """Input received and not accepted over a report period (rule 2).

    Attributes:
        unverified: handled, but held no verified message (datagrams; on a stream,
            packets: corrupt, unknown message ids, unsigned or wrongly signed on a
            signed link).
        shed: datagrams from strangers past the round's budget: read and dropped unparsed.
        period_ns: the time they came in, ns (from the previous report, or the first round).
    """

    unverified: int
    shed: int
    period_ns: int


class VehicleIo:
    """A vehicle's I/O on one transport (module rules); subclasses do the round.

    Args:
        endpoint: the vehicle; the adapter owns it from now on (closing closes it).
        link: the transport; the adapter owns it.
        clock: time for the I/O thread.
    """

    def __init__(self, endpoint: VehicleEndpoint, link: Closable, clock: Clock) -> None:
        self.endpoint = endpoint
        self.link = link
        self._clock = clock
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._closed = False
        self.packet_taps: list[Callable[[str, bytes, int], None]] = []
        """Called with every accepted packet in and packet out (rule 2)."""
        self.reject_observers: list[Callable[[Rejected, int], None]] = []
        """Called with the rejected traffic of a period and the time, ns (rule 2)."""
        self.unverified = 0
        """Input handled that held no verified message so far (rule 2)."""
        self._reported = (0, 0)  # (unverified, shed) at the last report
        self._report_ns: int | None = None

    @property
    def shed(self) -> int:
        """Datagrams from strangers dropped unparsed so far."""
        return self.endpoint.shed_datagrams

    def service(self, now_ns: int) -> None:
        """One round of I/O at ``now_ns`` (rules 1 and 3).

        Raises:
            LinkClosedError: the transport is closed or failed for good.
        """
        try:
            with self._lock:
                if self._closed:
                    return
                self._exchange(now_ns)
                self._report_rejects(now_ns)
        except LinkClosedError:
            raise
        except Exception as e:  # a bug; it must not end the link (rule 3)
            self.endpoint.faults.record("I/O round", e)

    def _exchange(self, now_ns: int) -> None:
        """Input in, packets out: the adapter's round (called with the lock held)."""
        raise NotImplementedError

    def _tap(self, direction: str, packet: bytes, now_ns: int) -> None:
        for tap in self.packet_taps:
            tap(direction, packet, now_ns)

    def _report_rejects(self, now_ns: int) -> None:
        """Rule 2: the counts of the period, once it is over and if it had any."""
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
                raise IllegalEventError(type(self).__name__, "CLOSED", "start_thread")
            if self._thread is None:
                self._thread = threading.Thread(
                    target=service_loop, name="mavlink-io", daemon=True,
                    args=(self.service, self._clock, self.endpoint.config.mavlink.service_period_ns,
                          self._stop, "vehicle"))
                self._thread.start()

    def close(self) -> None:
        """Stop the thread, close the endpoint and the transport; idempotent."""
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

    def __enter__(self) -> VehicleIo:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
