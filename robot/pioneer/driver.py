"""PioneerDriver: the Pioneer 3-AT as a :class:`~shared.interfaces.MobileBase`.

The driver owns the transport (a :class:`~shared.byte_link.ByteLink` made by
``link_factory``) and feeds the sans-I/O :class:`~robot.pioneer.client.PioneerClient`.

Rules:

1. :meth:`PioneerDriver.service` does one round of I/O: open the transport if due,
   read, run the client's timers, write. Either a lock-step loop calls it, or the
   driver's own I/O thread (:meth:`start_thread`, every ``service_period_ns``); never
   both.
2. Reconnection: when the session reports the link lost or the connect failed, or the
   transport raises :class:`LinkClosedError`, the transport is closed and re-opened
   through ``link_factory`` after a backoff (``reconnect_initial_ns``, doubling up to
   ``reconnect_max_ns``, reset by a completed connect), forever until :meth:`close`.
3. Commands go to the client at once and out on the next round; the client drops
   them while disconnected or while the motors are off (``client.py`` rule 3). Each is
   stamped with the clock's time when given: a round finding the last non-zero command
   older than ``command_timeout_ns`` sends zero instead of refreshing it (the command
   watchdog, ``client.py`` rule 4), so a stalled caller never leaves the robot driving.
4. Locks: ``_io_lock`` serialises service rounds and :meth:`close`; ``_lock`` guards
   the client and the event queue. Opening, reading, writing and closing the
   transport hold only ``_io_lock``, so callers of :meth:`command` and :meth:`state`
   never wait for a slow open (a TCP connect can take seconds). Both are re-entrant
   so that :meth:`close` works from a signal handler whatever the main thread holds.
5. A bug never ends the link: an exception of the client while it handles a round
   (anything but :class:`LinkClosedError`) is counted and logged once per kind
   (:attr:`PioneerDriver.faults`), and the link is treated as lost: closed, and
   re-opened with a fresh session after the backoff of rule 2. Meanwhile the robot's
   own watchdog stops it (ARCOS stops after 2 s without a packet).
6. Start-up: :meth:`open_transport` opens the transport once and raises if it cannot
   (the entry points call it first, so a wrong address is one line in about a second,
   not a stream of retries until their connect timeout). Once a transport is open, the
   handshake's retries and the reconnection of rule 2 are as above.
"""

from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable
from types import TracebackType

from robot.config import PioneerDriverConfig
from robot.pioneer.client import PioneerClient
from robot.pioneer.events import (
    CommandExpired,
    Connected,
    ConnectFailed,
    EStopPressed,
    LinkLost,
    LinkNoise,
    MotorsDisabled,
    PioneerEvent,
    Reconnecting,
    StaleStream,
    TransportFailed,
    UnknownSubtype,
)
from robot.pioneer.serial_link import serial_link_factory
from robot.pioneer.status import LinkCounters, LinkState, PioneerStatus
from shared.aria.sip import Sip
from shared.byte_link import ByteLink, LinkClosedError
from shared.clock import Clock, service_loop
from shared.errors import IllegalEventError, TransportError
from shared.handler_faults import HandlerFaults
from shared.interfaces import BaseState

logger = logging.getLogger(__name__)

EVENT_QUEUE_LEN = 1024
"""Events kept for :meth:`PioneerDriver.next_event`; the oldest go first when nobody reads."""
_WARNINGS = (ConnectFailed, LinkLost, StaleStream, UnknownSubtype, EStopPressed, MotorsDisabled,
             CommandExpired, LinkNoise, TransportFailed)


class PioneerDriver:
    """Velocity commands to, and odometry from, a Pioneer over ARIA.

    Args:
        link_factory: opens the transport; called again for every reconnection. It
            raises :class:`TransportError` when the transport cannot be opened.
        clock: time for the I/O thread and :meth:`wait_connected`.
        config: driver policy.
    """

    def __init__(self, link_factory: Callable[[], ByteLink], clock: Clock,
                 config: PioneerDriverConfig | None = None) -> None:
        self.config = config if config is not None else PioneerDriverConfig()
        self._link_factory = link_factory
        self._clock = clock
        self.sip_observers: list[Callable[[int, Sip], None]] = []
        """Called with (receive time, ns; the SIP) for every SIP decoded, on the thread that
        services the link with the driver's lock held: return at once, call no driver
        method (e.g. :meth:`robot.field_log.FieldLog.sip`). An exception is logged once
        and ignored."""
        self._observer_failed = False
        self._client = PioneerClient(self.config, on_sip=self._sip_received)
        self._link: ByteLink | None = None
        self._next_open_ns = 0
        self._failures = 0  # failed connections in a row
        self.faults = HandlerFaults(logger, "pioneer")
        """Exceptions of the client during a round (rule 5)."""
        self._events: deque[PioneerEvent] = deque(maxlen=EVENT_QUEUE_LEN)
        self._closed = False
        self._io_lock = threading.RLock()
        self._lock = threading.RLock()
        self._ready = threading.Condition(self._lock)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @classmethod
    def from_config(cls, config: PioneerDriverConfig, clock: Clock) -> PioneerDriver:
        """A driver on ``config.url`` through :class:`~robot.pioneer.serial_link.SerialLink`."""
        return cls(serial_link_factory(config.url, config.baud, config.write_timeout_s,
                                       config.connect_timeout_s), clock, config)

    # -- MobileBase -------------------------------------------------------------------

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Drive at ``v_m_s`` (m/s, forward +) and ``omega_rad_s`` (rad/s, CCW +) for at
        most ``config.command_timeout_ns``: call again to go on (module rule 3).

        Dropped (and counted) unless connected with the motors enabled.
        """
        with self._lock:
            self._client.command(v_m_s, omega_rad_s, self._clock.now_ns())

    def stop(self) -> None:
        """Command zero velocity."""
        with self._lock:
            self._client.stop(self._clock.now_ns())

    def state(self) -> BaseState:
        """Odometry, bumpers (front or rear), stall (either wheel), battery, motors, the
        sonars' latest readings; not ``reporting`` unless connected with a SIP within
        ``config.report_timeout_ns``."""
        s = self.status()
        now_ns = self._clock.now_ns()
        return BaseState(
            odom_pose=s.odom_pose,
            odom_distance_m=s.odom_distance_m,
            bumped=bool(s.front_bumpers or s.rear_bumpers),
            bumped_rear_only=bool(s.rear_bumpers and not s.front_bumpers),
            stalled=s.left_stalled or s.right_stalled,
            battery_v=s.battery_v,
            motors_enabled=s.motors_enabled,
            reporting=(s.link is LinkState.CONNECTED and s.last_sip_ns is not None
                       and now_ns - s.last_sip_ns <= self.config.report_timeout_ns),
            ranges=s.ranges,
        )

    # -- more than a MobileBase ---------------------------------------------------------

    def e_stop(self) -> None:
        """Stop at maximum deceleration (E_STOP), then hold zero velocity."""
        with self._lock:
            self._client.e_stop(self._clock.now_ns())

    def enable_motors(self) -> None:
        """Re-enable the motors (after the e-stop was released)."""
        with self._lock:
            self._client.enable_motors(self._clock.now_ns())

    def status(self) -> PioneerStatus:
        """The full snapshot: link state, odometry, velocities, power, safety."""
        with self._lock:
            return self._client.status

    def counters(self) -> LinkCounters:
        """Corrupt input, unexpected packets, SIPs, dropped commands, connects, losses."""
        with self._lock:
            return self._client.counters

    def next_event(self) -> PioneerEvent | None:
        """The oldest unread event, or None."""
        with self._lock:
            return self._events.popleft() if self._events else None

    # -- I/O ------------------------------------------------------------------------------

    def open_transport(self) -> None:
        """Open the transport now, once, before the first service round (rule 6): a missing
        device, an unknown host or a refused or unanswered connect is an error at once,
        not retried. Does nothing when the transport is open.

        Raises:
            TransportError: the transport cannot be opened (one line naming it).
            IllegalEventError: the driver is closed.
        """
        with self._io_lock:
            if self._closed:
                raise IllegalEventError("PioneerDriver", "CLOSED", "open_transport")
            if self._link is None:
                link = self._link_factory()
                with self._lock:
                    self._link = link
                    self._client.start(self._clock.now_ns())

    def service(self, now_ns: int) -> None:
        """One round of I/O at ``now_ns``: open if due, read, timers, write."""
        with self._io_lock:
            if self._closed:
                return
            link = self._link
            if link is None:
                if now_ns < self._next_open_ns:
                    return
                link = self._open_link(now_ns)
                if link is None:
                    return
            try:
                data = link.read_available()
                with self._lock:
                    self._client.receive_data(data, now_ns)
                    timer = self._client.get_timer()
                    if timer is not None and now_ns >= timer:
                        self._client.handle_timer(now_ns)
                    out = self._client.data_to_send()
                if out:
                    link.write(out)
            except LinkClosedError as e:
                with self._lock:
                    self._client.transport_lost(str(e))
            except Exception as e:  # a bug; it must not end the link (rule 5)
                self.faults.record("ARIA round", e)
                with self._lock:
                    self._client.transport_lost(f"internal error ({type(e).__name__})")
            with self._lock:
                self._collect_events()
                lost = self._client.link_state is LinkState.DISCONNECTED
                if lost:
                    self._link = None
                    self._schedule_reconnect(now_ns)
                if self._client.accepts_commands:
                    self._ready.notify_all()
            if lost:
                link.close()

    def _open_link(self, now_ns: int) -> ByteLink | None:
        try:
            link = self._link_factory()
        except TransportError as e:
            with self._lock:
                self._emit(TransportFailed(e.where, e.problem))
                self._schedule_reconnect(now_ns)
            return None
        with self._lock:
            self._link = link
            self._client.start(now_ns)
        return link

    def _schedule_reconnect(self, now_ns: int) -> None:
        cfg = self.config
        self._failures += 1
        delay_ns = min(cfg.reconnect_initial_ns << min(self._failures - 1, 32),
                       cfg.reconnect_max_ns)
        self._next_open_ns = now_ns + delay_ns
        self._emit(Reconnecting(self._failures, delay_ns))

    def _collect_events(self) -> None:
        while (event := self._client.next_event()) is not None:
            if isinstance(event, Connected):
                self._failures = 0
            self._emit(event)

    def _sip_received(self, now_ns: int, sip: Sip) -> None:
        for observer in self.sip_observers:
            try:
                observer(now_ns, sip)
            except Exception:  # an observer (a log) must never stop the robot's link
                if not self._observer_failed:
                    logger.exception("pioneer: a SIP observer failed; further failures "
                                     "are not logged")
                    self._observer_failed = True

    def _emit(self, event: PioneerEvent) -> None:
        logger.log(logging.WARNING if isinstance(event, _WARNINGS) else logging.INFO,
                   "pioneer: %s", event)
        self._events.append(event)

    # -- real time ------------------------------------------------------------------------

    def start_thread(self) -> None:
        """Service the link from a daemon thread every ``service_period_ns``; idempotent.

        Raises:
            IllegalEventError: the driver is closed.
        """
        with self._io_lock:
            if self._closed:
                raise IllegalEventError("PioneerDriver", "CLOSED", "start_thread")
            if self._thread is None:
                # Should it die (a bug), the robot's watchdog stops it within 2 s.
                self._thread = threading.Thread(
                    target=service_loop, name="pioneer-io", daemon=True,
                    args=(self.service, self._clock, self.config.service_period_ns, self._stop,
                          "pioneer"))
                self._thread.start()

    def wait_connected(self, timeout_ns: int) -> bool:
        """Wait until the robot is connected and reports its motors enabled.

        With the I/O thread running this waits for it; otherwise it services the link
        itself, sleeping on the clock between rounds (lock-step use).

        Args:
            timeout_ns: how long to wait, ns.

        Returns:
            True once ready to drive; False on timeout or after :meth:`close` (see
            :meth:`status`: not connected, e-stop pressed, ...).
        """
        deadline_ns = self._clock.now_ns() + timeout_ns
        if self._thread is not None:
            with self._ready:
                while not (self._client.accepts_commands or self._closed):
                    remaining_ns = deadline_ns - self._clock.now_ns()
                    if remaining_ns <= 0:
                        return False
                    self._ready.wait(remaining_ns / 1e9)
                return self._client.accepts_commands
        while True:
            now_ns = self._clock.now_ns()
            self.service(now_ns)
            with self._lock:
                if self._client.accepts_commands or self._closed:
                    return self._client.accepts_commands
            if now_ns >= deadline_ns:
                return False
            self._clock.sleep_until_ns(min(deadline_ns, now_ns + self.config.service_period_ns))

    def close(self) -> None:
        """Stop the I/O thread; send VEL 0, RVEL 0, ENABLE 0 and CLOSE if open; release the
        transport. Idempotent."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join()
        with self._io_lock:
            if self._closed:
                return
            with self._lock:
                self._closed = True
                self._client.close(self._clock.now_ns())
                out = self._client.data_to_send()
                link, self._link = self._link, None
                self._collect_events()
                self._ready.notify_all()
            if link is None:
                return
            try:
                if out:
                    link.write(out)
            except LinkClosedError as e:
                logger.info("pioneer: CLOSE not sent: %s", e)
            link.close()

    def __enter__(self) -> PioneerDriver:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
