"""PioneerClient: the host end of an ARIA link to a Pioneer 3-AT, sans-I/O.

Bytes in (``receive_data``), bytes out (``data_to_send``), deadlines via ``now_ns``
(``get_timer``/``handle_timer``), events out (``next_event``); the
:class:`~robot.pioneer.driver.PioneerDriver` owns the transport and the clock.

Rules:

1. One client lives for the whole run; every (re)opened transport gets a fresh
   :class:`AriaSession` through :meth:`PioneerClient.start`.
2. Connect as ARIA does (reference §3): SYNC0/1/2 (the session re-sends SYNC0 every
   ``sync_reply_timeout_ns`` and gives up after ``sync_attempts``), OPEN 1, CONFIG 1
   (re-requested every ``config_retry_ns``, given up after ``config_wait_ns``), then the
   motion limits (SETV, SETA ±, SETRV, SETRA ±, capped by CONFIG's tops) and ENABLE 1.
3. Velocity commands are taken only while connected with the motors enabled (as the
   robot reports them); otherwise they are dropped and counted, so the robot never
   lurches into an old command when the link or the motors come back. A lost link,
   disabled motors, an e-stop and E_STOP all reset the command to zero.
4. VEL and RVEL go out when their wire values change, and again every
   ``command_refresh_ns`` while the command is non-zero or the robot still reports
   wheel motion (ARIA's state reflection re-sends them; the protocol has no
   acknowledgement). When nothing else goes out, the session sends PULSE after 500 ms.
   The refresh never outlives its caller: a non-zero command given more than
   ``command_timeout_ns`` ago is replaced by zero (VEL 0, RVEL 0 go out, a
   :class:`CommandExpired` event, counted) until the next command; a caller that stopped
   commanding (a stalled loop) stops the robot (issue 15). ARIA has no such limit and
   keeps a crashed caller's last velocity alive (reference §7).
5. Odometry continues across reconnects (``odometry.py``).
6. SIPs during the handshake mean a previous connection was never closed: send CLOSE
   and SYNC0 again, at most once per ``sync_reply_timeout_ns`` (ARIA's recovery, §3).
7. Packet 0xFF or 0xFE from an open robot announces a controller reset: the link is
   lost (ARIA drops the connection, §3).
8. When the session declares the link lost, VEL 0, RVEL 0 and CLOSE still go out past
   it: on a half-open link the robot hears them and stops now rather than at its
   watchdog. Every connect also sends VEL 0 and RVEL 0 before ENABLE, because ARCOS
   resumes its last motion when packets return after its watchdog (reference §7).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from robot.config import PioneerDriverConfig
from robot.pioneer.events import (
    Closed,
    CommandExpired,
    Connected,
    ConnectFailed,
    EStopPressed,
    EStopReleased,
    LinkLost,
    LinkNoise,
    MotorsDisabled,
    MotorsEnabled,
    PioneerEvent,
    StaleStream,
    UnknownSubtype,
)
from robot.pioneer.odometry import DEFAULT_SUBTYPE, PARAMS_BY_SUBTYPE, Odometry, params_for_subtype
from robot.pioneer.status import LinkCounters, LinkState, PioneerStatus
from shared.aria import events as aria_events
from shared.aria.commands import ClientCommand, Command, enable, rvel, seta, setra, setrv, setv, vel
from shared.aria.config_packet import ConfigPacket
from shared.aria.events import Event, RawPacket, Sendable, UnexpectedPacket
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.session import AriaSession
from shared.aria.sip import Sip, SipFlags, SipType
from shared.aria.state import OPEN_STATES, ConnState, Role
from shared.errors import LocalProtocolError
from shared.interfaces import RangeReading

RESET_NOTICE_IDS = (0xFF, 0xFE)
"""Robot packets that announce a controller reset (reference §3, ``ArRobot.cpp:4546``)."""
_STOPPED = (0, 0)
_SIP_IDS = frozenset(int(t) for t in SipType)
_STALE_CLOSE_STATES = (ConnState.WAIT_SYNC0, ConnState.SYNC0_REQUESTED)
_FAREWELL = b"".join(command.to_packet().to_bytes()
                     for command in (vel(0.0), rvel(0.0), ClientCommand(Command.CLOSE, 1)))


class PioneerClient:
    """The host side of one robot, across reconnects.

    Args:
        config: driver policy; its ``link`` holds the session timers.
        on_sip: called with (receive time, ns; the SIP) for every SIP as it is decoded,
            after the odometry took it; None calls nothing.
    """

    def __init__(self, config: PioneerDriverConfig | None = None,
                 on_sip: Callable[[int, Sip], None] | None = None) -> None:
        self.config = config if config is not None else PioneerDriverConfig()
        self._on_sip_callback = on_sip
        self._session: AriaSession | None = None
        self._state = LinkState.DISCONNECTED
        self._outbox = bytearray()
        self._events: deque[PioneerEvent] = deque()
        self._odometry = Odometry()
        self._params = PARAMS_BY_SUBTYPE[DEFAULT_SUBTYPE]
        self._identity: RobotIdentity | None = None
        self._robot_config: ConfigPacket | None = None
        self._config_retry_ns: int | None = None  # set while waiting for CONFIG
        self._config_giveup_ns = 0
        self._command: tuple[int, int] = _STOPPED  # (VEL mm/s, RVEL deg/s) wire values
        self._sent: tuple[int, int] | None = None
        self._command_sent_ns = 0
        self._command_given_ns = 0  # when the caller gave self._command
        self._last_sip: Sip | None = None
        self._last_sip_ns: int | None = None
        self._ranges: dict[int, RangeReading] = {}  # this session's, by sonar number
        self._flags: SipFlags | None = None  # this session's last FLAGS
        self._stale_close_ns: int | None = None
        self._ended_session_noise = (0, 0, 0)  # bad checksums, skipped bytes, abandoned
        self._unexpected = 0
        self._sips = 0
        self._dropped = 0
        self._expired = 0
        self._connects = 0
        self._losses = 0
        self._noise_reported = (0, 0, 0, 0)
        self._noise_report_ns: int | None = None

    # -- state ----------------------------------------------------------------------

    @property
    def link_state(self) -> LinkState:
        """Where the client stands with the robot."""
        return self._state

    @property
    def accepts_commands(self) -> bool:
        """Connected, and the robot's last SIP says motors enabled and e-stop released."""
        flags = self._flags
        return (self._state is LinkState.CONNECTED and flags is not None
                and bool(flags & SipFlags.MOTORS_ENABLED)
                and not flags & SipFlags.ESTOP_PRESSED)

    @property
    def status(self) -> PioneerStatus:
        """What the robot last reported (see :class:`PioneerStatus`)."""
        sip, live = self._last_sip, self._state is LinkState.CONNECTED
        v_m_s = omega_rad_s = 0.0
        if live and sip is not None:
            v_m_s = (sip.left_vel_m_s + sip.right_vel_m_s) / 2
            if sip.rot_vel_rad_s is not None:
                omega_rad_s = sip.rot_vel_rad_s
            else:  # ARIA: (R - L) / 2 x DiffConvFactor, wheel speeds in mm/s
                diff_mm_s = (sip.right_vel_m_s - sip.left_vel_m_s) * 1000.0 / 2
                omega_rad_s = diff_mm_s * self._params.diff_conv_rad_per_mm
        return PioneerStatus(
            link=self._state,
            identity=self._identity,
            odom_pose=self._odometry.pose,
            odom_distance_m=self._odometry.distance_m,
            v_m_s=v_m_s,
            omega_rad_s=omega_rad_s,
            battery_v=_battery_v(sip),
            left_stalled=sip is not None and sip.left_stalled,
            right_stalled=sip is not None and sip.right_stalled,
            front_bumpers=sip.front_bumpers if sip is not None else 0,
            rear_bumpers=sip.rear_bumpers if sip is not None else 0,
            estop_pressed=sip is not None and bool(sip.flags & SipFlags.ESTOP_PRESSED),
            motors_enabled=self.accepts_commands,
            last_sip_ns=self._last_sip_ns,
            ranges=tuple(self._ranges[k] for k in sorted(self._ranges)),
        )

    @property
    def counters(self) -> LinkCounters:
        """Totals over every session so far."""
        bad, skipped, abandoned = self._ended_session_noise
        if self._session is not None:
            bad += self._session.bad_checksums
            skipped += self._session.skipped_bytes
            abandoned += self._session.abandoned_frames
        return LinkCounters(
            bad_checksums=bad, skipped_bytes=skipped, abandoned_frames=abandoned,
            unexpected_packets=self._unexpected, sips=self._sips, dropped_commands=self._dropped,
            connects=self._connects, link_losses=self._losses, expired_commands=self._expired,
        )

    def next_event(self) -> PioneerEvent | None:
        """The next event, or None."""
        return self._events.popleft() if self._events else None

    def data_to_send(self) -> bytes:
        """Take the bytes queued for the robot."""
        data = bytes(self._outbox)
        self._outbox.clear()
        return data

    # -- lifecycle ----------------------------------------------------------------------

    def start(self, now_ns: int) -> None:
        """Begin a connection on a freshly opened transport: queue SYNC0.

        Raises:
            LocalProtocolError: the client is not DISCONNECTED (connected, or closed).
        """
        if self._state is not LinkState.DISCONNECTED:
            raise LocalProtocolError(f"PioneerClient.start: state is {self._state.name}, "
                                     "not DISCONNECTED")
        self._session = AriaSession(Role.HOST, self.config.link)
        self._state = LinkState.CONNECTING
        self._outbox.clear()  # nothing meant for the previous transport
        self._robot_config = None
        self._flags = None
        self._ranges.clear()
        self._stale_close_ns = None
        self._odometry.restart()
        self._send(SyncRequest(0), now_ns)

    def transport_lost(self, reason: str) -> None:
        """The transport went away (the driver got ``LinkClosedError``)."""
        if self._state in (LinkState.CONNECTING, LinkState.CONNECTED):
            self._disconnect(LinkLost(reason))

    def close(self, now_ns: int) -> None:
        """Stop, disable the motors and CLOSE if open; then CLOSED for good. Idempotent."""
        if self._state is LinkState.CLOSED:
            return
        session = self._session
        if session is not None and session.state in OPEN_STATES:
            for event in (vel(0.0), rvel(0.0), enable(False), ClientCommand(Command.CLOSE, 1)):
                self._send(event, now_ns)
        elif session is not None and session.state is ConnState.CONNECTED:
            self._send(ClientCommand(Command.CLOSE, 1), now_ns)
        self._end_session()
        self._state = LinkState.CLOSED
        self._events.append(Closed())

    # -- commands ---------------------------------------------------------------------

    def command(self, v_m_s: float, omega_rad_s: float, now_ns: int) -> bool:
        """Drive at ``v_m_s`` (m/s, forward +) and ``omega_rad_s`` (rad/s, CCW +).

        Returns:
            True if taken; False if dropped (see rule 3).

        Raises:
            LocalProtocolError: a value is not finite.
        """
        wire = (_int_arg(vel(v_m_s)), _int_arg(rvel(omega_rad_s)))
        if not self.accepts_commands:
            self._dropped += 1
            return False
        self._set_command(wire, now_ns)
        return True

    def stop(self, now_ns: int) -> None:
        """Command zero velocity (VEL 0 and RVEL 0, as ``ArRobot::stop``)."""
        self._set_command(_STOPPED, now_ns)

    def e_stop(self, now_ns: int) -> None:
        """E_STOP (stop at maximum deceleration), then zero velocity; only while open."""
        if self._session is not None and self._session.state in OPEN_STATES:
            self._send(ClientCommand(Command.E_STOP), now_ns)
            self._sent = None  # re-send VEL 0 / RVEL 0 after it
        self._set_command(_STOPPED, now_ns)

    def enable_motors(self, now_ns: int) -> None:
        """ENABLE 1 again (after an e-stop); the robot refuses it while the button is down."""
        if self._state is LinkState.CONNECTED:
            self._send(enable(True), now_ns)

    def _set_command(self, wire: tuple[int, int], now_ns: int) -> None:
        self._command, self._command_given_ns = wire, now_ns
        if self._state is LinkState.CONNECTED and wire != self._sent:
            self._send_command(now_ns)

    def _send_command(self, now_ns: int) -> None:
        v_mm_s, omega_deg_s = self._command
        self._send(ClientCommand(Command.VEL, v_mm_s), now_ns)
        self._send(ClientCommand(Command.RVEL, omega_deg_s), now_ns)
        self._sent = self._command
        self._command_sent_ns = now_ns

    def _command_expires_ns(self) -> int | None:
        """When the current non-zero command expires (rule 4), ns; None if nothing to expire."""
        if self._state is not LinkState.CONNECTED or self._command == _STOPPED:
            return None
        return self._command_given_ns + self.config.command_timeout_ns

    def _expire_command(self, now_ns: int) -> None:
        """Replace a command older than ``command_timeout_ns`` by zero (rule 4)."""
        expires_ns = self._command_expires_ns()
        if expires_ns is None or now_ns < expires_ns:
            return
        self._expired += 1
        self._events.append(CommandExpired(now_ns - self._command_given_ns,
                                           self.config.command_timeout_ns))
        self._set_command(_STOPPED, now_ns)

    def _needs_refresh(self) -> bool:
        sip = self._last_sip
        moving = sip is not None and (sip.left_vel_m_s != 0 or sip.right_vel_m_s != 0)
        return self._state is LinkState.CONNECTED and (self._command != _STOPPED or moving)

    # -- input and timers ----------------------------------------------------------------

    def receive_data(self, data: bytes, now_ns: int) -> None:
        """Feed bytes from the robot (any chunking) and react to what they complete."""
        if self._session is None:
            return
        self._session.receive_data(data, now_ns)
        self._drain(now_ns)
        self._report_noise(now_ns)

    def get_timer(self) -> int | None:
        """The earliest deadline at which :meth:`handle_timer` has work, ns; None if none."""
        if self._session is None:
            return None
        deadlines = [t for t in (self._session.get_timer(), self._config_retry_ns) if t is not None]
        if self._config_retry_ns is not None:
            deadlines.append(self._config_giveup_ns)
        if self._needs_refresh():
            deadlines.append(self._command_sent_ns + self.config.command_refresh_ns)
        if (expires_ns := self._command_expires_ns()) is not None:
            deadlines.append(expires_ns)
        if self._noise_report_ns is not None and self._noise_totals() != self._noise_reported:
            deadlines.append(self._noise_report_ns + self.config.noise_report_period_ns)
        return min(deadlines) if deadlines else None

    def handle_timer(self, now_ns: int) -> None:
        """Do what is due: session timers (SYNC0 retry, PULSE, link loss), CONFIG retry,
        the expiry of an old command, else its refresh, a pending noise report. Safe to
        call early."""
        if self._session is None:
            return
        self._outbox += self._session.handle_timer(now_ns)
        self._drain(now_ns)
        if self._config_retry_ns is not None:
            if now_ns >= self._config_giveup_ns:
                self._finish_connect(now_ns)
            elif now_ns >= self._config_retry_ns:
                self._send(ClientCommand(Command.CONFIG, 1), now_ns)
                self._config_retry_ns = now_ns + self.config.config_retry_ns
        self._expire_command(now_ns)
        if (self._needs_refresh()
                and now_ns >= self._command_sent_ns + self.config.command_refresh_ns):
            self._send_command(now_ns)
        self._report_noise(now_ns)

    def _drain(self, now_ns: int) -> None:
        while self._session is not None and (event := self._session.next_event()) is not None:
            self._handle(event, now_ns)

    def _handle(self, event: Event, now_ns: int) -> None:
        match event:
            case SyncReply(seq=seq):
                self._send(SyncRequest(seq + 1), now_ns)
            case RobotIdentity():
                self._on_identity(event, now_ns)
            case ConfigPacket():
                self._robot_config = event
                if self._config_retry_ns is not None:
                    self._finish_connect(now_ns)
            case Sip():
                self._on_sip(event, now_ns)
            case UnexpectedPacket(packet=packet):
                self._unexpected += 1
                if packet.packet_id in _SIP_IDS:
                    self._close_stale(now_ns)
            case RawPacket(packet_id=pid) if pid in RESET_NOTICE_IDS:
                self._disconnect(LinkLost(f"the robot announced a controller reset "
                                          f"(packet 0x{pid:02X})"), farewell=True)
            case aria_events.ConnectFailed(attempts=attempts):
                self._disconnect(ConnectFailed(attempts))
            case aria_events.LinkLost(silence_ns=silence_ns):
                limit_s = self.config.link.link_timeout_ns / 1e9
                self._disconnect(LinkLost(f"no SIP for {silence_ns / 1e9:.1f} s "
                                          f"(limit {limit_s:.1f} s)"), farewell=True)
            case _:  # corrupt frames and encoder packets: counted by the session or unused
                pass

    def _on_identity(self, identity: RobotIdentity, now_ns: int) -> None:
        self._identity = identity
        params = params_for_subtype(identity.subclass)
        if params is None:
            self._events.append(UnknownSubtype(identity.subclass, DEFAULT_SUBTYPE))
            params = PARAMS_BY_SUBTYPE[DEFAULT_SUBTYPE]
        self._params = params
        self._send(ClientCommand(Command.OPEN, 1), now_ns)
        self._send(ClientCommand(Command.CONFIG, 1), now_ns)
        self._config_retry_ns = now_ns + self.config.config_retry_ns
        self._config_giveup_ns = now_ns + self.config.config_wait_ns

    def _finish_connect(self, now_ns: int) -> None:
        """Push the motion limits (capped by CONFIG's tops), enable the motors."""
        cfg, top = self.config, self._robot_config
        self._config_retry_ns = None
        v_max, omega_max = cfg.max_speed_m_s, cfg.max_omega_rad_s
        accel, rot_accel = cfg.accel_m_s2, cfg.rot_accel_rad_s2
        if top is not None:
            v_max = _capped(v_max, top.trans_vel_top_m_s)
            omega_max = _capped(omega_max, top.rot_vel_top_rad_s)
            accel = _capped(accel, top.trans_accel_top_m_s2)
            rot_accel = _capped(rot_accel, top.rot_accel_top_rad_s2)
        for event in (setv(v_max), seta(accel), seta(-cfg.decel_m_s2), setrv(omega_max),
                      setra(rot_accel), setra(-cfg.rot_decel_rad_s2)):
            self._send(event, now_ns)
        self._state = LinkState.CONNECTED
        self._command = _STOPPED
        self._send_command(now_ns)
        self._send(enable(True), now_ns)
        self._connects += 1
        assert self._identity is not None  # set by _on_identity before CONFIG was asked
        self._events.append(Connected(self._identity, self._robot_config))

    def _on_sip(self, sip: Sip, now_ns: int) -> None:
        self._sips += 1
        self._odometry.update(sip, self._params)
        self._last_sip, self._last_sip_ns = sip, now_ns
        poses = self._params.sonar_poses
        for reading in sip.sonar:
            if reading.number < len(poses):  # a sonar the robot's params do not place
                self._ranges[reading.number] = RangeReading(
                    reading.number, poses[reading.number], reading.range_m, now_ns,
                    self._odometry.pose)
        if self._on_sip_callback is not None:
            self._on_sip_callback(now_ns, sip)
        before, self._flags = self._flags, sip.flags
        for bit, on_event, off_event in (
            (SipFlags.ESTOP_PRESSED, EStopPressed(), EStopReleased()),
            (SipFlags.MOTORS_ENABLED, MotorsEnabled(), MotorsDisabled()),
        ):
            was, now = before is not None and bool(before & bit), bool(sip.flags & bit)
            if now and not was:
                self._events.append(on_event)
            elif was and not now:
                self._events.append(off_event)
        if not self.accepts_commands and self._command != _STOPPED:
            self._set_command(_STOPPED, now_ns)

    def _close_stale(self, now_ns: int) -> None:
        session = self._session
        if session is None or session.state not in _STALE_CLOSE_STATES:
            return
        last = self._stale_close_ns
        if last is not None and now_ns < last + self.config.link.sync_reply_timeout_ns:
            return
        self._stale_close_ns = now_ns
        self._send(ClientCommand(Command.CLOSE, 1), now_ns)
        self._send(SyncRequest(0), now_ns)
        self._events.append(StaleStream())

    def _disconnect(self, event: ConnectFailed | LinkLost, farewell: bool = False) -> None:
        if isinstance(event, LinkLost):
            self._losses += 1
        if farewell:
            self._outbox += _FAREWELL
        self._end_session()
        self._state = LinkState.DISCONNECTED
        self._events.append(event)

    def _end_session(self) -> None:
        """Fold the session's counters into the totals and drop it; motion is stopped."""
        session = self._session
        if session is not None:
            bad, skipped, abandoned = self._ended_session_noise
            self._ended_session_noise = (bad + session.bad_checksums,
                                         skipped + session.skipped_bytes,
                                         abandoned + session.abandoned_frames)
        self._session = None
        self._config_retry_ns = None
        self._command, self._sent = _STOPPED, None
        self._flags = None

    def _send(self, event: Sendable, now_ns: int) -> None:
        assert self._session is not None
        self._outbox += self._session.send(event, now_ns)

    def _noise_totals(self) -> tuple[int, int, int, int]:
        c = self.counters
        return c.bad_checksums, c.skipped_bytes, c.abandoned_frames, c.unexpected_packets

    def _report_noise(self, now_ns: int) -> None:
        totals = self._noise_totals()
        last_ns = self._noise_report_ns
        if totals == self._noise_reported or (
                last_ns is not None and now_ns < last_ns + self.config.noise_report_period_ns):
            return
        deltas = (now - before for now, before in zip(totals, self._noise_reported, strict=True))
        self._events.append(LinkNoise(*deltas))
        self._noise_reported, self._noise_report_ns = totals, now_ns


def _capped(value: float, top: float) -> float:
    """``value`` limited to a CONFIG top; a top of 0 means none announced."""
    return min(value, top) if top > 0 else value


def _int_arg(command: ClientCommand) -> int:
    """The int argument the SI helpers always produce."""
    assert isinstance(command.arg, int)
    return command.arg


def _battery_v(sip: Sip | None) -> float:
    """BATTERYX10 when sent (finer), else BATTERY, V; 0.0 before any SIP."""
    if sip is None:
        return 0.0
    return sip.real_battery_v or sip.battery_v
