"""Serving the emulated Pioneer on byte links, one client at a time, tick by physics tick.

Rules:

1. **Links.** Fixed links (a pty, or any :class:`~shared.byte_link.ByteLink` such as
   an in-memory pipe) and TCP listeners. A tick reads every link.
2. **One client at a time.** The active link is the one that last sent bytes, and
   replies go to it alone. Bytes from another link mean another client: the robot
   stops and a new session begins (:meth:`EmulatedPioneer.reset_session`).
3. **TCP.** One TCP client at a time: another one that connects meanwhile is
   accepted and closed at once (refused). The client's socket is closed when the
   client closes it, when it fails, or after the client's CLOSE (aria-protocol.md
   §11 rule 7); then the robot stops and the next client may connect. A pty stays
   open after CLOSE: the session waits for SYNC0 (rule 7 for serial links).
4. **A tick** is one physics step: step the simulation (the emulator's firmware
   runs in its step hook), feed the bytes received meanwhile, stamped with the new
   time, accept or refuse TCP clients (after the reads, so a client that has just
   left makes room for the next), service the emulator, and write its bytes to the
   active link. :meth:`PioneerServer.pump` is the tick without the step, for
   lock-step loops that step the simulation themselves.
5. **Real time.** :meth:`PioneerServer.run` ticks on a clock's deadlines one physics
   step apart (a :class:`~shared.clock.WallClock` makes it real time) until
   :meth:`PioneerServer.stop` or the duration. Falling behind by more than
   :data:`MAX_LAG_NS` drops the backlog rather than racing to catch up.
6. :meth:`PioneerServer.close` releases every link, listener and client; idempotent.
7. **Faults** (issue 8's fault tests; callable from any thread, applied at the next
   tick). :meth:`PioneerServer.cut` pulls the cable for a stretch of simulation
   time: every byte is lost both ways (what clients send is read and dropped,
   nothing is written to them), while connections open and close as usual; the
   emulator's watchdog sees a silent client. :meth:`PioneerServer.inject` sends
   bytes to the active client ahead of the next tick's output (line noise, or a
   device that is no Pioneer); without an active client, or during a cut, they wait.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Sequence

from shared.aria import ConnState
from shared.byte_link import ByteLink, LinkClosedError
from shared.clock import Clock
from sim.pioneer.emulator import EmulatedPioneer
from sim.pioneer.links import StreamLink, TcpListener

log = logging.getLogger(__name__)

MAX_LAG_NS = 500_000_000
"""Real-time loop: behind the clock by more than this, skip ahead instead, ns."""


class PioneerServer:
    """An :class:`EmulatedPioneer` on byte links (see the module rules). Owns the links.

    Args:
        emulator: the robot (its simulation is stepped here).
        links: fixed links, e.g. a :class:`~sim.pioneer.links.PtyLink`.
        listeners: TCP listeners.
    """

    def __init__(
        self,
        emulator: EmulatedPioneer,
        links: Sequence[ByteLink] = (),
        listeners: Sequence[TcpListener] = (),
    ) -> None:
        self.emulator = emulator
        self.links = list(links)
        self.listeners = list(listeners)
        self.refused_clients = 0
        """TCP clients closed at once because another one was connected."""
        self._tcp_client: StreamLink | None = None
        self._active: ByteLink | None = None
        self._stop = threading.Event()
        self._faults = threading.Lock()  # guards the two requests below (rule 7)
        self._cut_request_ns: int | None = None
        self._noise = bytearray()
        self._cut_until_ns = 0  # the loop's: bytes are lost while sim time is before this

    def __enter__(self) -> PioneerServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- one tick -----------------------------------------------------------------

    def tick(self) -> None:
        """One physics step with its I/O (rule 4)."""
        self.emulator.simulation.step()
        self.pump()

    def pump(self) -> None:
        """The I/O of a tick without the step: for a lock-step loop that steps the
        simulation itself (a :class:`~sim.sim_clock.SimClock`), run it as a step hook,
        ``simulation.add_step_hook(lambda now_ns, dt_ns: server.pump())``."""
        sim, emulator = self.emulator.simulation, self.emulator
        cut = self._cut_now(sim.now_ns)
        for link in self._readable():
            try:
                data = link.read_available()
            except LinkClosedError as e:
                self._drop(link, e.problem)
                continue
            if data and not cut:
                self._activate(link)
                emulator.receive_data(data, sim.now_ns)
        self._accept()  # after the reads: a client that just left has been noticed
        out = emulator.service(sim.now_ns)
        active = self._active
        if active is None:
            return
        if cut:
            out = b""
        elif self._noise:
            with self._faults:
                out, self._noise = bytes(self._noise) + out, bytearray()
        try:
            active.write(out)
        except LinkClosedError as e:
            self._drop(active, e.problem)
            return
        if active is self._tcp_client and emulator.state is ConnState.CLOSED:
            self._drop(active, "closed after the client's CLOSE")

    def _cut_now(self, now_ns: int) -> bool:
        """Whether the cable is cut at ``now_ns`` (rule 7), starting a requested cut."""
        if self._cut_request_ns is not None:
            with self._faults:
                self._cut_until_ns = now_ns + self._cut_request_ns
                self._cut_request_ns = None
        return now_ns < self._cut_until_ns

    def _readable(self) -> list[ByteLink]:
        client = self._tcp_client
        return [*self.links, client] if client is not None else list(self.links)

    def _accept(self) -> None:
        for listener in self.listeners:
            while (client := listener.accept()) is not None:
                if self._tcp_client is None:
                    log.info("ARIA client connected on %s", client.where)
                    self._tcp_client = client
                else:
                    log.info("ARIA client on %s refused: %s is connected", client.where,
                             self._tcp_client.where)
                    self.refused_clients += 1
                    client.close()

    def _activate(self, link: ByteLink) -> None:
        """Rule 2: bytes from ``link``; a different client than before restarts the session."""
        if self._active is not None and link is not self._active:
            log.info("a client on another link took over; the robot stops, new session")
            self.emulator.reset_session()
        self._active = link

    def _drop(self, link: ByteLink, reason: str) -> None:
        """Close ``link`` and forget it; the robot stops if it was the client's."""
        log.info("ARIA link %s closed: %s", _name(link), reason)
        link.close()
        if link is self._tcp_client:
            self._tcp_client = None
        elif link in self.links:
            self.links.remove(link)
        if link is self._active:
            self._active = None
            self.emulator.reset_session()

    # -- faults (rule 7) ------------------------------------------------------------

    def cut(self, duration_ns: int) -> None:
        """Lose every byte both ways for the next ``duration_ns`` of simulation time, from
        the next tick (replaces a cut in progress; 0 mends it)."""
        with self._faults:
            self._cut_request_ns = duration_ns

    def inject(self, data: bytes) -> None:
        """Send ``data`` to the active client ahead of the next tick's output (after a cut
        in progress)."""
        with self._faults:
            self._noise += data

    # -- the real-time loop ---------------------------------------------------------

    def run(self, clock: Clock, duration_ns: int | None = None) -> None:
        """Tick one physics step apart on ``clock`` until :meth:`stop` or ``duration_ns``.

        Returns at once if :meth:`stop` was called before. Does not close the links.
        """
        dt_ns = self.emulator.simulation.config.physics_dt_ns
        deadline = clock.now_ns()
        end = None if duration_ns is None else deadline + duration_ns
        while not self._stop.is_set():
            deadline += dt_ns
            if end is not None and deadline > end:
                return
            clock.sleep_until_ns(deadline)
            self.tick()
            lag_ns = clock.now_ns() - deadline
            if lag_ns > MAX_LAG_NS:
                log.warning("simulation %.2f s behind real time; skipping ahead", lag_ns / 1e9)
                deadline += lag_ns

    def stop(self) -> None:
        """Make :meth:`run` return after the current tick; safe from any thread or a
        signal handler."""
        self._stop.set()

    def close(self) -> None:
        """Close every link, listener and client (rule 6)."""
        for link in self.links:
            link.close()
        for listener in self.listeners:
            listener.close()
        if self._tcp_client is not None:
            self._tcp_client.close()
            self._tcp_client = None
        self._active = None


def _name(link: ByteLink) -> str:
    """The link's transport for log messages (``where`` of the adapters in ``links``)."""
    return str(getattr(link, "where", type(link).__name__))
