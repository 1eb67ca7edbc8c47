"""Client commands (host -> robot): opcodes, argument encoding, SI helpers.

A command packet's body is ``ID [ARGTYPE ARG...]`` (reference §2;
``ArRobotPacketSender.h:109``). Argument encodings and their byte-order quirks:

* ``0x3B`` positive int: a **little-endian uint16 magnitude** follows.
* ``0x1B`` negative int: the value is **-(magnitude)**, a sign byte plus a
  magnitude, *not* two's complement. ``VEL -200`` is ``0B 1B C8 00``.
* ``0x2B`` string: one length byte, then that many bytes. ARIA's ``comStr`` sends an
  extra, uncounted NUL, which the decoder accepts.
* data (ARIA ``comDataN``, MobileSim's SETO x/y/th and SIM_SET_POSE): one type byte
  (ignored by the server), then raw little-endian fields and no length byte.
* VEL2 packs two signed bytes (left wheel high, right wheel low) into an int16 and
  sends *that* with the sign-byte encoding, so a negative left wheel makes the whole
  argument negative (:func:`vel2`, :func:`vel2_wheels`).

Wire units stop here. The helpers (:func:`vel`, :func:`rvel`, :func:`head`, ...) take
SI values and round and clamp them to what the wire carries;
:attr:`ClientCommand.si_value` converts a received argument back to SI.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from enum import IntEnum

from shared.aria._wire import DECIVOLT, DEG, DEG_S, DEG_S2, MM, MM_S, MM_S2, WireUnit
from shared.aria.framing import MAX_DATA_LEN, Packet
from shared.errors import LocalProtocolError, RemoteProtocolError

INT16_LIMIT = 0x7FFF
"""Largest magnitude the helpers send: ARIA's ``comInt`` takes a C ``short``."""
MAGNITUDE_LIMIT = 0xFFFF
"""Largest magnitude the sign-byte encoding can carry."""


class Command(IntEnum):
    """Client command numbers (reference §4; ARIA ``ArCommands.h``). Units are ARCOS defaults."""

    PULSE = 0  #: no arg; keep-alive (the same bytes as SYNC0)
    OPEN = 1  #: no arg (ARIA sends int 1); start the servers and the SIP stream
    CLOSE = 2  #: no arg (ARIA sends int 1); stop and end the connection
    POLLING = 3  #: str arg; sonar polling sequence, one sonar number per byte
    ENABLE = 4  #: int arg 1/0; motors on/off; refused while the e-stop is engaged
    SETA = 5  #: signed int arg; + translational accel, - translational decel, mm/s²
    SETV = 6  #: int arg; maximum translational velocity, mm/s
    SETO = 7  #: no arg (MobileSim: data arg, x y th int16); reset odometry to 0, 0, 0
    MOVE = 8  #: signed int arg; relative translation, mm
    ROTATE = 9  #: signed int arg; rotational velocity, deg/s (MobileSim: same as RVEL)
    SETRV = 10  #: int arg; maximum rotational velocity, deg/s
    VEL = 11  #: signed int arg; translational velocity, mm/s
    HEAD = 12  #: signed int arg; absolute heading, deg (ARIA sends -180..180)
    DHEAD = 13  #: signed int arg; relative heading, deg
    SAY = 15  #: str arg; buzzer: (duration in 20 ms units, tone) byte pairs
    JOYINFO = 17  #: int arg 0/1/2; joystick packets: stop / one / continuous
    CONFIG = 18  #: int arg; request a CONFIGpac (0x20)
    ENCODER = 19  #: int arg 0/1/2; ENCODERpac (0x90): stop / one / continuous
    SETRVDIR = 20  #: signed int arg; per-direction maximum rotational velocity, deg/s
    RVEL = 21  #: signed int arg; rotational velocity, deg/s
    DCHEAD = 22  #: signed int arg; Colbert relative heading setpoint, deg
    SETRA = 23  #: signed int arg; + rotational accel, - rotational decel, deg/s²
    SONAR = 28  #: int arg 1/0; all sonar arrays on/off
    STOP = 29  #: no arg; stop, motors stay enabled
    DIGOUT = 30  #: int arg; high byte = mask, low byte = values of the digital outputs
    VEL2 = 32  #: signed int arg, packed; left high byte, right low byte, Vel2Divisor units
    GRIPPER = 33  #: int arg; gripper server command
    ADSEL = 35  #: int arg; analog port reported in the SIP's ANPORT/ANALOG
    GRIPPERVAL = 36  #: int arg; gripper server value
    GRIPREQUEST = 37  #: int arg; gripper packet request
    IOREQUEST = 40  #: int arg 0/1/2; IOpac (0xF0): stop / one / continuous
    BUMPSTALL = 44  #: int arg 0-3; stall on front (1), rear (2), both (3) bumpers
    JOYDRIVE = 47  #: int arg 1/0; allow driving with the robot's joystick
    HOSTBAUD = 50  #: int arg 0-4; host port baud 9600/19200/38400/57600/115200
    AUX1BAUD = 51  #: int arg 0-4; AUX1 port baud, codes as HOSTBAUD
    AUX2BAUD = 52  #: int arg 0-4; AUX2 port baud, codes as HOSTBAUD
    AUX3BAUD = 53  #: int arg 0-4; AUX3 port baud, codes as HOSTBAUD
    E_STOP = 55  #: no arg (ARIA adds int 1); stop at maximum deceleration
    E_STALL = 56  #: int arg 1/0; enable E_STALL
    GYRO = 58  #: int arg 1/0; GYROpac (0x98) on/off
    BATTERYINFO = 62  #: int arg 0/1/2; MTX battery packets (0xFA); SRISim's old EXIT
    ROTKP = 82  #: int arg; rotation PID proportional gain
    ROTKV = 83  #: int arg; rotation PID derivative gain
    ROTKI = 84  #: int arg; rotation PID integral gain
    TRANSKP = 85  #: int arg; translation PID proportional gain
    TRANSKV = 86  #: int arg; translation PID derivative gain
    TRANSKI = 87  #: int arg; translation PID integral gain
    REVCOUNT = 88  #: int arg; encoder counts per 180 deg turn (P3-AT about 16500)
    DRIFTFACTOR = 89  #: signed int arg; odometry drift correction
    SOUNDTOG = 92  #: int arg 1/0; buzzer on/off
    TICKSMM = 93  #: int arg; encoder ticks per mm (P3-AT 128)
    SIM_SET_POSE = 224  #: data arg, int32 x mm, y mm, th deg; MobileSim: move the true pose
    SIM_RESET = 225  #: no arg; MobileSim: back to the start pose, odometry 0, 0, 0
    SIM_MODEL_CONFIG = 226  #: data arg; MobileSim: robot model parameters
    SIM_LRF_ENABLE = 230  #: int arg 0/1/2; MobileSim: simulated laser off / on / extended
    SIM_LRF_SET_FOV_START = 231  #: signed int arg; MobileSim: laser start angle, deg
    SIM_LRF_SET_FOV_END = 232  #: signed int arg; MobileSim: laser end angle, deg
    SIM_LRF_SET_RES = 233  #: int arg; MobileSim: laser angular resolution, deg
    SIM_CTRL = 236  #: data arg, int16 operation first; MobileSim meta-command
    SIM_STAT = 237  #: no arg; MobileSim: reply with a SIMSTAT (0x62) packet
    SIM_MESSAGE = 238  #: str arg; MobileSim: show a log message
    SIM_EXIT = 239  #: int arg; MobileSim: exit with this code
    BATTEST = 250  #: int arg; fake battery voltage, decivolts (0 = real)
    RESET = 253  #: no arg; MobileSim aborts on it, an emulator logs and ignores it
    MAINTENANCE = 255  #: no arg; MobileSim aborts on it, an emulator logs and ignores it


class ArgType(IntEnum):
    """The type byte that starts a command argument (``ArRobotPacketSender.h:109``)."""

    INT = 0x3B  #: positive int; uint16 LE magnitude follows
    NEG_INT = 0x1B  #: negative int; uint16 LE magnitude follows, value = -magnitude
    STR = 0x2B  #: string; length byte, then that many bytes (also comDataN, without length)


DATA_COMMANDS = frozenset(
    {Command.SETO, Command.SIM_SET_POSE, Command.SIM_MODEL_CONFIG, Command.SIM_CTRL}
)
"""Commands whose non-int argument is raw data (type byte, no length byte), never a string."""

WIRE_UNITS: dict[Command, WireUnit] = {
    Command.SETA: MM_S2,
    Command.SETV: MM_S,
    Command.MOVE: MM,
    Command.ROTATE: DEG_S,
    Command.SETRV: DEG_S,
    Command.VEL: MM_S,
    Command.HEAD: DEG,
    Command.DHEAD: DEG,
    Command.SETRVDIR: DEG_S,
    Command.RVEL: DEG_S,
    Command.DCHEAD: DEG,
    Command.SETRA: DEG_S2,
    Command.SIM_LRF_SET_FOV_START: DEG,
    Command.SIM_LRF_SET_FOV_END: DEG,
    Command.SIM_LRF_SET_RES: DEG,
    Command.BATTEST: DECIVOLT,
}
"""The wire unit of each command whose int argument is a physical quantity."""


@dataclass(frozen=True, slots=True)
class DataArg:
    """A raw argument: a type byte (servers ignore it), then fields with no length byte.

    Attributes:
        payload: the raw bytes after the type byte.
        type_byte: the leading type byte; ARIA's ``comDataN`` uses 0x2B.
    """

    payload: bytes
    type_byte: int = ArgType.STR

    def __post_init__(self) -> None:
        if not 0 <= self.type_byte <= 0xFF:
            raise LocalProtocolError(f"DataArg type byte {self.type_byte} is outside 0..255")


@dataclass(frozen=True, slots=True)
class ClientCommand:
    """A command from the host to the robot (an event of the session).

    Attributes:
        command: which command.
        arg: ``None`` (no argument), an ``int`` in -65535..65535 (sign byte + uint16
            magnitude; the helpers keep to int16 as ARIA does), ``bytes`` (a
            length-prefixed string argument, at most 250 bytes) or a :class:`DataArg`.

    Raises:
        LocalProtocolError: on an unknown command number or an argument that does not fit.
    """

    command: Command
    arg: int | bytes | DataArg | None = None

    def __post_init__(self) -> None:
        try:
            Command(self.command)
        except ValueError:
            raise LocalProtocolError(f"unknown command number {self.command!r}") from None
        self.to_packet()  # validates the argument's size and range

    def to_packet(self) -> Packet:
        """The command's packet: ID = command number, DATA = encoded argument."""
        return Packet(int(self.command), _encode_arg(self.command, self.arg))

    @classmethod
    def from_packet(cls, packet: Packet) -> ClientCommand:
        """Decode a received command packet (robot role).

        An argument that is neither a well-formed int nor a string (nor empty) comes
        back as a :class:`DataArg`, so a server never has to reject a packet for its
        argument; it checks the argument's type where it cares.

        Raises:
            RemoteProtocolError: the ID is not a known command.
        """
        try:
            command = Command(packet.packet_id)
        except ValueError:
            raise RemoteProtocolError(f"unknown command number {packet.packet_id}") from None
        return cls(command, _decode_arg(command, packet.data))

    @property
    def si_value(self) -> float:
        """The int argument in SI units (m, m/s, m/s², rad, rad/s, rad/s², V).

        Raises:
            RemoteProtocolError: the argument is not an int.
            ValueError: the command's argument has no physical unit (see :data:`WIRE_UNITS`).
        """
        unit = WIRE_UNITS.get(self.command)
        if unit is None:
            raise ValueError(f"{self.command.name} carries no physical unit")
        if not isinstance(self.arg, int):
            raise RemoteProtocolError(
                f"{self.command.name}: expected an int argument, got {self.arg!r}"
            )
        return unit.si(self.arg)


def _encode_arg(command: Command, arg: int | bytes | DataArg | None) -> bytes:
    if arg is None:
        return b""
    if isinstance(arg, int):
        if not -MAGNITUDE_LIMIT <= arg <= MAGNITUDE_LIMIT:
            raise LocalProtocolError(
                f"{Command(command).name}: int argument {arg} is outside "
                f"±{MAGNITUDE_LIMIT} (sign byte + uint16 magnitude)"
            )
        kind = ArgType.INT if arg >= 0 else ArgType.NEG_INT
        return bytes((kind,)) + abs(arg).to_bytes(2, "little")
    if isinstance(arg, bytes):
        if len(arg) > MAX_DATA_LEN - 2:
            raise LocalProtocolError(
                f"{Command(command).name}: string argument of {len(arg)} bytes exceeds "
                f"{MAX_DATA_LEN - 2}"
            )
        return bytes((ArgType.STR, len(arg))) + bytes(arg)
    if isinstance(arg, DataArg):
        return bytes((arg.type_byte,)) + arg.payload
    raise LocalProtocolError(
        f"{Command(command).name}: argument must be int, bytes, DataArg or None, "
        f"got {type(arg).__name__}"
    )


def _decode_arg(command: Command, data: bytes) -> int | bytes | DataArg | None:
    if not data:
        return None
    kind = data[0]
    if kind in (ArgType.INT, ArgType.NEG_INT) and len(data) == 3:
        magnitude = int.from_bytes(data[1:3], "little")
        return magnitude if kind == ArgType.INT else -magnitude
    if kind == ArgType.STR and command not in DATA_COMMANDS and len(data) >= 2:
        length, extra = data[1], len(data) - 2 - data[1]
        if extra == 0 or (extra == 1 and data[-1] == 0):
            return bytes(data[2 : 2 + length])
    return DataArg(bytes(data[1:]), kind)


# ---------------------------------------------------------------------------
# SI helpers for the host role: round, clamp to int16 as ARIA's comInt does.
# ---------------------------------------------------------------------------


def _signed(command: Command, name: str, value: float) -> ClientCommand:
    unit = WIRE_UNITS[command]
    return ClientCommand(command, unit.clamped(name, value, -INT16_LIMIT, INT16_LIMIT))


def _unsigned(command: Command, name: str, value: float) -> ClientCommand:
    unit = WIRE_UNITS[command]
    return ClientCommand(command, unit.clamped(name, value, 0, INT16_LIMIT))


def vel(v_m_s: float) -> ClientCommand:
    """VEL: translational velocity, m/s -> mm/s, rounded, clamped to ±32767."""
    return _signed(Command.VEL, "vel: v_m_s", v_m_s)


def rvel(omega_rad_s: float) -> ClientCommand:
    """RVEL: rotational velocity, rad/s (counter-clockwise +) -> deg/s, clamped to ±32767."""
    return _signed(Command.RVEL, "rvel: omega_rad_s", omega_rad_s)


def rotate(omega_rad_s: float) -> ClientCommand:
    """ROTATE: rotational velocity, rad/s -> deg/s (MobileSim treats it as RVEL)."""
    return _signed(Command.ROTATE, "rotate: omega_rad_s", omega_rad_s)


def move(distance_m: float) -> ClientCommand:
    """MOVE: relative translation, m -> mm, clamped to ±32767."""
    return _signed(Command.MOVE, "move: distance_m", distance_m)


def head(heading_rad: float) -> ClientCommand:
    """HEAD: absolute heading, rad -> whole degrees normalized to 0..359 (the manual's range)."""
    if not math.isfinite(heading_rad):
        raise LocalProtocolError(f"head: heading_rad: must be finite, got {heading_rad!r}")
    return ClientCommand(Command.HEAD, round(math.degrees(heading_rad)) % 360)


def dhead(delta_rad: float) -> ClientCommand:
    """DHEAD: heading change relative to the current heading, rad -> deg."""
    return _signed(Command.DHEAD, "dhead: delta_rad", delta_rad)


def dchead(delta_rad: float) -> ClientCommand:
    """DCHEAD: Colbert relative heading setpoint, rad -> deg."""
    return _signed(Command.DCHEAD, "dchead: delta_rad", delta_rad)


def setv(v_max_m_s: float) -> ClientCommand:
    """SETV: maximum translational velocity, m/s -> mm/s, clamped to 0..32767."""
    return _unsigned(Command.SETV, "setv: v_max_m_s", v_max_m_s)


def setrv(omega_max_rad_s: float) -> ClientCommand:
    """SETRV: maximum rotational velocity, rad/s -> deg/s, clamped to 0..32767."""
    return _unsigned(Command.SETRV, "setrv: omega_max_rad_s", omega_max_rad_s)


def setrvdir(omega_max_rad_s: float) -> ClientCommand:
    """SETRVDIR: per-direction maximum rotational velocity (sign picks it), rad/s -> deg/s."""
    return _signed(Command.SETRVDIR, "setrvdir: omega_max_rad_s", omega_max_rad_s)


def seta(accel_m_s2: float) -> ClientCommand:
    """SETA: translational acceleration (> 0) or deceleration (< 0), m/s² -> mm/s²."""
    return _signed(Command.SETA, "seta: accel_m_s2", accel_m_s2)


def setra(accel_rad_s2: float) -> ClientCommand:
    """SETRA: rotational acceleration (> 0) or deceleration (< 0), rad/s² -> deg/s²."""
    return _signed(Command.SETRA, "setra: accel_rad_s2", accel_rad_s2)


def battest(voltage_v: float) -> ClientCommand:
    """BATTEST: make the robot report this battery voltage, V -> decivolts (0 = real)."""
    return _unsigned(Command.BATTEST, "battest: voltage_v", voltage_v)


def enable(on: bool) -> ClientCommand:
    """ENABLE 1 / ENABLE 0: motors on or off."""
    return ClientCommand(Command.ENABLE, 1 if on else 0)


def vel2(left_m_s: float, right_m_s: float, divisor_m_s: float) -> ClientCommand:
    """VEL2: independent wheel velocities, packed as ARIA's state reflector does.

    Each wheel becomes a signed byte in units of ``divisor_m_s`` (the robot's
    Vel2Divisor: 20 mm/s on a P3), clamped to -128..127; left is the high byte,
    right the low byte, and the int16 they form goes out with the sign-byte encoding
    (reference §2: left -5, right +5 -> ``20 1B FB 04``).

    Args:
        left_m_s: left wheel velocity, m/s.
        right_m_s: right wheel velocity, m/s.
        divisor_m_s: the robot's Vel2Divisor, m/s, > 0.
    """
    if not (math.isfinite(divisor_m_s) and divisor_m_s > 0):
        raise LocalProtocolError(f"vel2: divisor_m_s must be > 0, got {divisor_m_s!r}")
    unit = WireUnit("Vel2Divisor", 1 / divisor_m_s)
    left = unit.clamped("vel2: left_m_s", left_m_s, -128, 127)
    right = unit.clamped("vel2: right_m_s", right_m_s, -128, 127)
    packed = (left & 0xFF) << 8 | (right & 0xFF)
    return ClientCommand(Command.VEL2, packed - 0x10000 if packed & 0x8000 else packed)


def vel2_wheels(arg: int) -> tuple[int, int]:
    """Split a received VEL2 argument into (left, right) signed bytes, Vel2Divisor units.

    The sign of ``arg`` is applied before splitting (MobileSim ``case VEL2``).
    """
    left, right = struct.unpack(">bb", (arg & 0xFFFF).to_bytes(2, "big"))
    return left, right


def sim_set_pose(x_m: float, y_m: float, th_rad: float) -> ClientCommand:
    """SIM_SET_POSE (MobileSim): move the simulated robot's true pose; odometry is untouched.

    Args:
        x_m: x in the simulator's world frame, m (sent as int32 mm).
        y_m: y, m (int32 mm).
        th_rad: heading, rad (int32 whole degrees).
    """
    limit = 2**31 - 1
    payload = struct.pack(
        "<iii",
        MM.wire("sim_set_pose: x_m", x_m, -limit, limit),
        MM.wire("sim_set_pose: y_m", y_m, -limit, limit),
        DEG.wire("sim_set_pose: th_rad", th_rad, -limit, limit),
    )
    return ClientCommand(Command.SIM_SET_POSE, DataArg(payload))
