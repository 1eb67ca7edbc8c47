"""The emulated Pioneer 3-AT-SH: an ARIA server (robot role) on the simulation's body.

Sans-I/O: bytes in with :meth:`EmulatedPioneer.receive_data`, bytes out of
:meth:`EmulatedPioneer.service`, time as ``now_ns`` (the simulation's time). The
transports and the real-time loop are in :mod:`sim.pioneer.server`. The firmware's
motion control runs in a step hook of the simulation (:mod:`sim.pioneer.motion`), so
it acts every physics step whatever the service rate.

Rules (aria-protocol.md §11, the emulator checklist):

1. **Handshake.** SYNC0 and SYNC1 are echoed; SYNC2 is answered with ``name``,
   ``Pioneer``, ``p3at-sh``. An out-of-sequence packet restarts at SYNC0 (the
   session's rule). No SIP goes out before OPEN.
2. **Commands** are obeyed only while open (ARCOS starts its servers at OPEN); others
   are counted as ignored, as are commands not emulated (POLLING, HOSTBAUD,
   BATTERYINFO, SIM_*, RESET, ...). Packets whose ID is no command are counted as
   unknown. An int argument outside a C short (-32768..32767, what ARIA's ``comInt``
   can send), or an ENABLE or SONAR other than 0 or 1, is refused and counted; values
   within it are clamped as ARCOS does (velocities to the SETV/SETRV maxima, those
   and the accelerations to the CONFIG tops, headings wrapped).
3. **SIPs** go out every ``sip_period_ns`` from OPEN, always of type 0x32 (MobileSim
   does the same; a stale stream of 0x33 blocks ARIA's reconnect, §3). Positions are
   the body's wheel odometry (never the truth) since power-up or SETO, in the
   15-bit wrapped counts of DistConvFactor 1.0 mm; the groups run through FAULTFLAGS
   (82 bytes with 16 sonar readings, under the 128 old ARIA clients can read).
   Every field is clamped to its width at encoding: a BATTEST above 25.5 V reports
   25.5 V in the u8 BATTERY and the full value in the u16 BATTERYX10.
4. **CONFIG** is answered with the flash values and the current maxima and
   accelerations, never zero (§6).
5. **Watchdog.** No client packet for ``watchdog_timeout_ns`` stops the robot until
   packets return, then it drives on (ARCOS); with ``watchdog_stops = False`` it is
   only counted (MobileSim).
6. **CLOSE** stops the robot and turns the motors off; the session waits for SYNC0
   (serial, pty). A TCP server closes the socket on it (:attr:`EmulatedPioneer.state`
   is CLOSED) and calls :meth:`EmulatedPioneer.reset_session` for the next client.
7. **A stale session.** A new client's SYNC0 reaching a session still open (the old
   client died) reads as PULSE; the 0x32 SIPs answer it, ARIA sends CLOSE (rule 6:
   the robot stops) and then SYNC0, and a new session begins.
8. **Odometry and battery persist** across connections, as on the robot; motion
   limits, motors, SONAR and BATTEST return to their power-up state.
9. **Nothing a client sends ends the emulator.** An exception while handling a
   received packet or a due SIP is caught and counted (``handler_errors``), and logged
   once per kind (event and exception type); the session goes on with the next packet.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple, cast

import numpy as np

from shared.aria import (
    AriaSession,
    ChargeState,
    ClientCommand,
    Command,
    ConfigPacket,
    ConnState,
    Event,
    RobotIdentity,
    Role,
    Sip,
    SipDue,
    SipFlags,
    SipIo,
    SipType,
    SonarReading,
    SyncReply,
    SyncRequest,
    UnexpectedPacket,
    WatchdogCleared,
    WatchdogExpired,
    vel2_wheels,
    wrap_position,
)
from shared.aria.p3at import (
    ANGLE_CONV_RAD,
    DIFF_CONV_RAD_PER_M,
    DIST_CONV_M,
    FRONT_BUMPER_SEGMENTS,
    REAR_BUMPER_SEGMENTS,
    ROBOT_CLASS,
    SUBCLASS,
    THPOS_UNITS_PER_TURN,
    VEL2_DIVISOR_M_S,
)
from shared.aria.state import OPEN_STATES
from shared.errors import ConfigError, LocalProtocolError
from shared.handler_faults import HandlerFaults
from shared.pose import Pose2
from sim.config import EmulatorConfig
from sim.pioneer.motion import MotionController
from sim.pioneer.sonar import SonarRing
from sim.simulation import Simulation

log = logging.getLogger(__name__)

_SONAR_FLAGS = SipFlags.SONAR_ARRAY_1 | SipFlags.SONAR_ARRAY_2  # a P3-AT has two arrays
_SESSION_COMMANDS = (Command.PULSE, Command.OPEN, Command.CLOSE)
_COMMAND_IDS = frozenset(int(c) for c in Command)
_INT_ARG_RANGE = (-0x8000, 0x7FFF)
"""The int arguments obeyed: a C short, what ARIA's ``comInt`` sends (rule 2)."""
_FLAG_ARGS = (0, 1)
"""The arguments ENABLE and SONAR take (off, on)."""

# The widest values the SIP's fields carry (rule 3; reference §5), SI units.
_SIP_BATTERY_MAX_V = 0xFF / 10
"""BATTERY, u8 decivolts: 25.5 V."""
_SIP_BATTERYX10_MAX_V = 0xFFFF / 10
"""BATTERYX10, u16 decivolts: 6553.5 V."""
_SIP_WHEEL_MAX_M_S = 0x7FFF / 1000
"""LVEL/RVEL, s16 mm/s: 32.767 m/s."""
_SIP_ROTVEL_MAX_RAD_S = math.radians(0x7FFF / 10)
"""ROTVEL, s16 in 0.1 deg/s: 3276.7 deg/s."""
_SIP_RANGE_MAX_M = 0xFFFF / 1000
"""Sonar RANGE, u16 mm: 65.535 m."""


class _Handler(NamedTuple):
    """How the emulator obeys one command."""

    needs_int: bool
    """The command is ignored unless its argument is an int."""
    run: Callable[[ClientCommand], None]
    int_args: tuple[int, ...] | None = None
    """The only int arguments obeyed (others are refused); None: any in a C short."""


@dataclass(frozen=True, slots=True)
class EmulatorStats:
    """What the emulator has seen since it was made, over all sessions (counts)."""

    sessions: int
    """Sessions begun: the first, plus one per :meth:`EmulatedPioneer.reset_session`."""
    sips_sent: int
    commands: int
    """Commands obeyed (PULSE and OPEN included)."""
    ignored_commands: int
    """Known commands not emulated, sent before OPEN, or with an argument of the wrong kind."""
    refused_commands: int
    """Commands with an int argument out of range (outside a C short; ENABLE, SONAR not 0/1)."""
    unknown_commands: int
    """Well-framed packets whose ID is no command."""
    unexpected_packets: int
    """Other packets out of place (an out-of-sequence SYNC, a command during the handshake)."""
    bad_checksums: int
    skipped_bytes: int
    """Bytes dropped while hunting for a frame header."""
    abandoned_frames: int
    """Partial frames given up after the frame timeout."""
    watchdog_trips: int
    handler_errors: int
    """Exceptions caught while handling a received packet or a due SIP (rule 9)."""


class EmulatedPioneer:
    """A P3-AT-SH speaking ARIA on ``simulation``'s body (see the module rules).

    Args:
        simulation: the world; the emulator drives its body and registers a step hook.
        config: name, battery, sonar, watchdog policy and link timing.
        rng: source of the sonar noise.

    Raises:
        ConfigError: the link timing does not fit the CONFIG packet (SIP cycle
            over 255 ms, watchdog over 65535 ms, or not whole milliseconds).
    """

    def __init__(
        self, simulation: Simulation, config: EmulatorConfig, rng: np.random.Generator
    ) -> None:
        self.simulation = simulation
        self.config = config
        self._body = simulation.body
        self.identity = RobotIdentity(config.name, ROBOT_CLASS, SUBCLASS)
        self._flash = _flash(config, simulation)
        self._motion = MotionController(self._flash)
        self._sonar = SonarRing(simulation.space, config, rng)
        self._origin = Pose2(0.0, 0.0, 0.0)
        self._wheel_travel_m = 0.0
        self._battest_v: float | None = None
        self._counts: Counter[str] = Counter(sessions=1)
        self._session = AriaSession(Role.ROBOT, config.link)
        self._handlers = self._command_handlers()
        self._faults = HandlerFaults(log, "emulated Pioneer")
        simulation.add_step_hook(self._on_step)

    # -- state --------------------------------------------------------------------

    @property
    def state(self) -> ConnState:
        """The connection state of the current session."""
        return self._session.state

    @property
    def motors_enabled(self) -> bool:
        """Whether the motors are on (SIP FLAGS bit 0)."""
        return self._motion.motors_enabled

    @property
    def battery_v(self) -> float:
        """The battery voltage the SIP reports, V (BATTEST's value while one is set)."""
        if self._battest_v is not None:
            return self._battest_v
        drained = self.config.battery_drain_v_per_m * self._wheel_travel_m
        return max(self.config.battery_empty_v, self.config.battery_full_v - drained)

    @property
    def stats(self) -> EmulatorStats:
        """Counters over all sessions."""
        c, s = self._counts, self._session
        return EmulatorStats(
            sessions=c["sessions"],
            sips_sent=c["sips_sent"],
            commands=c["commands"],
            ignored_commands=c["ignored_commands"],
            refused_commands=c["refused_commands"],
            unknown_commands=c["unknown_commands"],
            unexpected_packets=c["unexpected_packets"],
            bad_checksums=c["bad_checksums"] + s.bad_checksums,
            skipped_bytes=c["skipped_bytes"] + s.skipped_bytes,
            abandoned_frames=c["abandoned_frames"] + s.abandoned_frames,
            watchdog_trips=c["watchdog_trips"],
            handler_errors=c["handler_errors"],
        )

    # -- the sans-I/O surface -------------------------------------------------------

    def receive_data(self, data: bytes, now_ns: int) -> None:
        """Feed bytes from the client (any chunking) that arrived at ``now_ns`` (ns)."""
        self._session.receive_data(data, now_ns)

    def service(self, now_ns: int) -> bytes:
        """Handle what was received and what is due at ``now_ns`` (ns); returns bytes to send.

        Call it often (every physics step, or every 10 ms): SIPs go out at the first
        call on or after their cycle time.
        """
        out = bytearray(self._drain(now_ns))  # packets first: they may clear the watchdog
        deadline = self._session.get_timer()
        if deadline is not None and now_ns >= deadline:
            out += self._session.handle_timer(now_ns)
            out += self._drain(now_ns)
        return bytes(out)

    def reset_session(self) -> None:
        """A new client: the robot stops, motors off, and a fresh session waits for SYNC0."""
        s = self._session
        self._counts.update(
            bad_checksums=s.bad_checksums,
            skipped_bytes=s.skipped_bytes,
            abandoned_frames=s.abandoned_frames,
            sessions=1,
        )
        self._session = AriaSession(Role.ROBOT, self.config.link)
        self._end_connection()

    def press_stop_button(self, pressed: bool) -> None:
        """Press or release the red STOP button: pressed stops the robot, turns the motors
        off and refuses ENABLE; after release the motors stay off until ENABLE 1."""
        self._motion.press_stop_button(pressed)

    # -- events ---------------------------------------------------------------------

    def _drain(self, now_ns: int) -> bytes:
        out = bytearray()
        while True:
            event: Event | None = None
            try:
                event = self._session.next_event()
                if event is None:
                    return bytes(out)
                out += self._handle(event, now_ns)
            except Exception as e:  # rule 9: no client byte ends the server
                self._count_error(event, e)
                if event is None:  # the session itself failed: try again at the next call
                    return bytes(out)

    def _count_error(self, event: Event | None, error: Exception) -> None:
        """Rule 9: count an exception from handling ``event``; log its first of a kind."""
        self._counts["handler_errors"] += 1
        what = type(event).__name__ if not isinstance(event, ClientCommand) else (
            f"command {event.command.name}")
        self._faults.record(what, error)

    def _handle(self, event: Event, now_ns: int) -> bytes:
        session = self._session
        if isinstance(event, SyncRequest):
            reply = SyncReply(event.seq) if event.seq < 2 else self.identity
            return session.send(reply, now_ns)
        if isinstance(event, ClientCommand):
            return self._obey(event, now_ns)
        if isinstance(event, SipDue) and session.state in OPEN_STATES:
            self._counts["sips_sent"] += 1
            return session.send(self._sip(), now_ns)
        if isinstance(event, WatchdogExpired):
            self._counts["watchdog_trips"] += 1
            if self.config.watchdog_stops:
                self._motion.halt()
        elif isinstance(event, WatchdogCleared):
            self._motion.resume()
        elif isinstance(event, UnexpectedPacket):
            known = event.packet.packet_id in _COMMAND_IDS
            self._counts["unexpected_packets" if known else "unknown_commands"] += 1
        return b""  # CorruptPacket: the session counts it

    def _obey(self, event: ClientCommand, now_ns: int) -> bytes:
        command, arg = event.command, event.arg
        if command not in _SESSION_COMMANDS and self._session.state not in OPEN_STATES:
            self._counts["ignored_commands"] += 1
            return b""
        if command is Command.CONFIG:
            self._counts["commands"] += 1
            return self._session.send(self._motion.limits, now_ns)
        handler = self._handlers.get(command)
        if handler is None or (handler.needs_int and not isinstance(arg, int)):
            self._counts["ignored_commands"] += 1
            return b""
        if handler.needs_int and not _int_arg_obeyed(cast(int, arg), handler):
            self._counts["refused_commands"] += 1
            return b""
        self._counts["commands"] += 1
        handler.run(event)
        return b""

    def _command_handlers(self) -> dict[Command, _Handler]:
        """How each emulated command (but CONFIG, which answers) is obeyed."""
        m = self._motion

        def si(action: Callable[[float], None]) -> _Handler:
            return _Handler(True, lambda e: action(e.si_value))

        def flag(action: Callable[[bool], object]) -> _Handler:
            return _Handler(True, lambda e: action(e.arg != 0), _FLAG_ARGS)

        def plain(action: Callable[[], None]) -> _Handler:
            return _Handler(False, lambda e: action())

        def vel2(e: ClientCommand) -> None:
            left, right = vel2_wheels(cast(int, e.arg))
            m.set_wheels(left * VEL2_DIVISOR_M_S, right * VEL2_DIVISOR_M_S)

        return {
            Command.PULSE: plain(lambda: None),
            Command.OPEN: plain(lambda: None),
            Command.CLOSE: plain(self._end_connection),
            Command.ENABLE: flag(m.enable),
            Command.E_STOP: plain(m.e_stop),
            Command.STOP: plain(m.stop),
            Command.VEL: si(m.set_velocity),
            Command.RVEL: si(m.set_rot_velocity),
            Command.ROTATE: si(m.set_rot_velocity),
            Command.VEL2: _Handler(True, vel2),
            Command.MOVE: si(lambda d: m.move(d, self._odom_pose())),
            Command.HEAD: si(m.set_heading),
            Command.DHEAD: si(lambda d: m.turn_by(d, self._odom_pose())),
            Command.DCHEAD: si(lambda d: m.turn_setpoint_by(d, self._odom_pose())),
            Command.SETV: si(m.set_max_velocity),
            Command.SETRV: si(m.set_max_rot_velocity),
            Command.SETA: si(m.set_accel),
            Command.SETRA: si(m.set_rot_accel),
            Command.SETO: plain(self._reset_odometry),
            Command.SONAR: flag(self._sonar.enable),
            Command.BATTEST: si(self._set_battest),
        }

    def _end_connection(self) -> None:
        self._motion.reset()
        self._sonar.take_readings()
        self._sonar.enable(True)
        self._battest_v = None

    def _reset_odometry(self) -> None:
        self._origin = self._body.odom_pose

    def _set_battest(self, voltage_v: float) -> None:
        self._battest_v = voltage_v if voltage_v > 0 else None

    # -- the body -------------------------------------------------------------------

    def _on_step(self, now_ns: int, dt_ns: int) -> None:
        """Step hook: the firmware's profile commands the body; battery; sonar pings."""
        dt_s = dt_ns / 1e9
        self._body.command(*self._motion.step(dt_s, self._odom_pose()))
        left, right = _wheels(*self._body.odom_velocity)
        self._wheel_travel_m += (abs(left) + abs(right)) / 2 * dt_s
        self._sonar.fire_due(now_ns, self._body.pose_w)

    def _odom_pose(self) -> Pose2:
        """The body's wheel odometry in the frame of the last SETO."""
        x, y, th = self._body.odom_pose
        x0, y0, th0 = self._origin
        c, s = math.cos(th0), math.sin(th0)
        dx, dy = x - x0, y - y0
        return Pose2(c * dx + s * dy, -s * dx + c * dy, th - th0)

    def _sip(self) -> Sip:
        body, motion = self._body, self._motion
        x, y, th = self._odom_pose()
        v, omega = body.odom_velocity
        left, right = _wheels(v, omega)
        heading_target = motion.heading_target_rad
        flags = SipFlags(0)
        if motion.motors_enabled:
            flags |= SipFlags.MOTORS_ENABLED
        if self._sonar.enabled:
            flags |= _SONAR_FLAGS
        if motion.stop_button_pressed:
            flags |= SipFlags.ESTOP_PRESSED
        battery = self.battery_v
        return Sip(
            sip_type=SipType.STOPPED,
            x_counts=wrap_position(round(x / DIST_CONV_M)),
            y_counts=wrap_position(round(y / DIST_CONV_M)),
            th_counts=_thpos(th),
            left_vel_m_s=_clamp(left, _SIP_WHEEL_MAX_M_S),
            right_vel_m_s=_clamp(right, _SIP_WHEEL_MAX_M_S),
            battery_v=min(battery, _SIP_BATTERY_MAX_V),
            left_stalled=body.stalled,
            right_stalled=body.stalled,
            front_bumpers=FRONT_BUMPER_SEGMENTS if body.bumped_front else 0,
            rear_bumpers=REAR_BUMPER_SEGMENTS if body.bumped_rear else 0,
            control_counts=_thpos(th if heading_target is None else heading_target),
            flags=flags,
            sonar=tuple(SonarReading(n, min(r, _SIP_RANGE_MAX_M))
                        for n, r in self._sonar.take_readings()),
            io=SipIo(),
            real_battery_v=min(battery, _SIP_BATTERYX10_MAX_V),
            charge_state=ChargeState.NOT_CHARGING,
            rot_vel_rad_s=_clamp(omega, _SIP_ROTVEL_MAX_RAD_S),
            fault_flags=0,
        )


def _int_arg_obeyed(arg: int, handler: _Handler) -> bool:
    """Whether int argument ``arg`` is in range for ``handler`` (rule 2)."""
    if handler.int_args is not None:
        return arg in handler.int_args
    lo, hi = _INT_ARG_RANGE
    return lo <= arg <= hi


def _clamp(value: float, limit: float) -> float:
    """``value`` limited to ``-limit..limit``."""
    return max(-limit, min(limit, value))


def _wheels(v_m_s: float, omega_rad_s: float) -> tuple[float, float]:
    """(left, right) wheel velocities, m/s: v -/+ omega / DiffConv (reference §5)."""
    offset = omega_rad_s / DIFF_CONV_RAD_PER_M
    return v_m_s - offset, v_m_s + offset


def _thpos(heading_rad: float) -> int:
    """A heading, rad, as THPOS units wrapped to -2048..2047."""
    half = THPOS_UNITS_PER_TURN // 2
    return (round(heading_rad / ANGLE_CONV_RAD) + half) % THPOS_UNITS_PER_TURN - half


def _flash(config: EmulatorConfig, simulation: Simulation) -> ConfigPacket:
    """The robot's stored configuration: ConfigPacket defaults, this robot's name, link
    timing, and tops no faster than the simulated body can go."""
    base, body = ConfigPacket(), simulation.config.body
    trans_top = min(base.trans_vel_top_m_s, body.max_speed_m_s)
    rot_top = min(base.rot_vel_top_rad_s, body.max_omega_rad_s)
    flash = ConfigPacket(
        robot_class=ROBOT_CLASS,
        subclass=SUBCLASS,
        name=config.name,
        sip_cycle_ns=config.link.sip_period_ns,
        watchdog_ns=config.link.watchdog_timeout_ns,
        trans_vel_top_m_s=trans_top,
        rot_vel_top_rad_s=rot_top,
        trans_vel_max_m_s=min(base.trans_vel_max_m_s, trans_top),
        rot_vel_max_rad_s=min(base.rot_vel_max_rad_s, rot_top),
    )
    try:
        flash.to_packet()
    except LocalProtocolError as e:
        raise ConfigError("emulator link timing", str(e)) from None
    return flash
