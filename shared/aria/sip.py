"""Server information packets about motion: the standard SIP and the ENCODERpac.

Standard SIP layout (reference §5; ARIA ``ArRobot::processMotorPacket``, MobileSim
``SIPGenerator::getPacket``), offsets in DATA, little-endian throughout::

    0  XPOS  u16   position, counts; only the low 15 bits count (wraps at 0x8000)
    2  YPOS  u16   same
    4  THPOS s16   heading, AngleConvFactor units (0.001534 rad, about 2 pi / 4096)
    6  LVEL  s16   left wheel, mm/s            8  RVEL s16   right wheel, mm/s
    10 BATTERY u8  decivolts                   11 STALL_AND_BUMPERS u16
    13 CONTROL s16 heading setpoint, THPOS units
    15 FLAGS u16   (SipFlags)                  17 COMPASS u8  2 deg units, 0 = none
    18 SONAR_COUNT u8, then SONAR_COUNT x (NUMBER u8, RANGE u16 mm)
    then optional groups, each present only if bytes remain (ARIA reads a group
    only while ``remaining > 0``, so a robot must send whole groups, in order):
    GRIP_STATE ANPORT ANALOG DIGIN DIGOUT (5 x u8) | BATTERYX10 u16 dV |
    CHARGESTATE u8 | ROTVEL s16 0.1 deg/s | FAULTFLAGS u16 | LATVEL s16 mm/s |
    TEMPERATURE s8 degC | STATE_OF_CHARGE u8 % | uC time u32 us | FLAGS3 u32

Positions stay in raw counts: converting them needs the robot's DistConvFactor and
AngleConvFactor (reference §8), which belong to the driver. :func:`position_delta`
unwraps the 15-bit counters; everything else is converted to SI here.

Keep SIPs under 128 bytes for old ARIA clients (the signed-COUNT bug, reference §1);
16 sonar readings and all groups through STATE_OF_CHARGE fit.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, fields
from enum import IntEnum, IntFlag

from shared.aria._wire import DECIDEG_S, DECIVOLT, MM, MM_S, TWO_DEG
from shared.aria.framing import Packet
from shared.errors import LocalProtocolError, RemoteProtocolError

POSITION_MASK = 0x7FFF
"""XPOS/YPOS carry 15 bits (ARIA masks with 0x7FFF)."""
ENCODER_PACKET_ID = 0x90


class SipType(IntEnum):
    """The standard SIP's packet ID."""

    STOPPED = 0x32  #: motors stopped; MobileSim's only type; ARIA's stale-link recovery needs it
    MOVING = 0x33  #: robot moving; a stale link streaming it blocks ARIA's reconnect (ref. §3)
    TYPE_34 = 0x34  #: accepted as a SIP by p2os (0x30-0x34); meaning undocumented; ARIA ignores it


class SipFlags(IntFlag):
    """FLAGS bits (P3 manual, Table 8); bits 11-15 are reserved and kept as they come."""

    MOTORS_ENABLED = 1 << 0
    SONAR_ARRAY_1 = 1 << 1
    SONAR_ARRAY_2 = 1 << 2
    SONAR_ARRAY_3 = 1 << 3
    SONAR_ARRAY_4 = 1 << 4
    ESTOP_PRESSED = 1 << 5
    E_STALL = 1 << 6
    FAR_LEDGE_IR = 1 << 7
    NEAR_LEDGE_IR = 1 << 8
    JOYSTICK_BUTTON = 1 << 9
    CHARGER_POWER_GOOD = 1 << 10


NO_FLAGS = SipFlags(0)


class ChargeState(IntEnum):
    """CHARGESTATE values (Pioneer LX guide p.116)."""

    NOT_CHARGING = 0
    BULK = 1
    OVERCHARGE = 2
    FLOAT = 3
    BALANCE = 4
    UNKNOWN = 255  # -1 as a byte


@dataclass(frozen=True, slots=True)
class SonarReading:
    """One new sonar reading.

    Attributes:
        number: sonar index, 0..255 (P3-AT: 0-7 front, 8-15 rear).
        range_m: range, m (u16 mm on the wire; RangeConvFactor is 1.0 on a P3).
    """

    number: int
    range_m: float


@dataclass(frozen=True, slots=True)
class SipIo:
    """The first optional SIP group: gripper and user I/O, one byte each."""

    grip_state: int = 0
    anport: int = 0
    """Analog port selected with ADSEL."""
    analog: int = 0
    """Reading of that port, 0-255 = 0-5 V."""
    digin: int = 0
    digout: int = 0


@dataclass(frozen=True, slots=True)
class Sip:
    """The standard SIP (motor packet), SI units except the raw position counters.

    Optional groups are ``None`` when absent. They form a prefix: if a group is
    present, every group before it is present too.

    Raises:
        LocalProtocolError: a position outside 0..0x7FFF, a bumper mask outside 7 bits,
            or an optional group present after an absent one.
    """

    sip_type: SipType = SipType.STOPPED
    x_counts: int = 0
    """XPOS, 15 bits: x = counts x DistConvFactor mm (P3-AT-SH 1.0, P3-AT 0.465)."""
    y_counts: int = 0
    """YPOS, 15 bits."""
    th_counts: int = 0
    """THPOS, s16: heading = counts x AngleConvFactor rad (0.001534)."""
    left_vel_m_s: float = 0.0
    """Left wheel velocity, m/s (s16 mm/s)."""
    right_vel_m_s: float = 0.0
    """Right wheel velocity, m/s (s16 mm/s)."""
    battery_v: float = 0.0
    """Battery, V (u8 decivolts)."""
    left_stalled: bool = False
    right_stalled: bool = False
    rear_bumpers: int = 0
    """Rear bumper segments, bit mask, 7 bits."""
    front_bumpers: int = 0
    """Front bumper segments, bit mask, 7 bits."""
    control_counts: int = 0
    """CONTROL, s16: heading setpoint, THPOS units."""
    flags: SipFlags = NO_FLAGS
    compass_rad: float = 0.0
    """Compass heading, rad (u8 in 2 deg units; 0 without a compass)."""
    sonar: tuple[SonarReading, ...] = ()
    """New sonar readings; the count byte is their number."""
    io: SipIo | None = None
    real_battery_v: float | None = None
    """BATTERYX10, V (u16 decivolts); ARIA's getRealBatteryVoltage."""
    charge_state: int | None = None
    """CHARGESTATE, see :class:`ChargeState`."""
    rot_vel_rad_s: float | None = None
    """ROTVEL, rad/s (s16, 0.1 deg/s)."""
    fault_flags: int | None = None
    lat_vel_m_s: float | None = None
    """LATVEL, m/s (s16 mm/s; Seekur only)."""
    temperature_c: int | None = None
    """TEMPERATURE, degC (s8; MobileSim sends -127 for none)."""
    state_of_charge_pct: int | None = None
    uc_time_us: int | None = None
    """Microcontroller time, us (u32, MTX)."""
    flags3: int | None = None
    """FLAGS3 (u32, MTX)."""

    def __post_init__(self) -> None:
        if self.sip_type not in tuple(SipType):
            raise LocalProtocolError(f"Sip.sip_type: {self.sip_type!r} is not a SIP type")
        for name in ("x_counts", "y_counts"):
            value = getattr(self, name)
            if not 0 <= value <= POSITION_MASK:
                raise LocalProtocolError(
                    f"Sip.{name}: {value} is outside the 15-bit counter 0..0x7FFF "
                    "(wrap with wrap_position)"
                )
        for name in ("rear_bumpers", "front_bumpers"):
            value = getattr(self, name)
            if not 0 <= value <= 0x7F:
                raise LocalProtocolError(f"Sip.{name}: {value} is outside the 7-bit mask 0..0x7F")
        names = [name for name, _, _ in _TAIL]
        gap = next((k for k, name in enumerate(names) if getattr(self, name) is None), len(names))
        for name in names[gap + 1 :]:
            if getattr(self, name) is not None:
                raise LocalProtocolError(
                    f"Sip.{name} is set but the earlier group Sip.{names[gap]} is None: "
                    "optional groups are sent in order"
                )

    @property
    def motors_enabled(self) -> bool:
        """FLAGS bit 0."""
        return bool(self.flags & SipFlags.MOTORS_ENABLED)

    def to_packet(self) -> Packet:
        """Encode (ID = ``sip_type``).

        Raises:
            LocalProtocolError: a value does not fit its wire field (message names it).
        """
        stall_bumpers = (
            int(self.left_stalled) | self.rear_bumpers << 1
            | int(self.right_stalled) << 8 | self.front_bumpers << 9
        )
        parts = [_pack(
            "Sip", _FIXED,
            self.x_counts, self.y_counts, self.th_counts,
            MM_S.wire("Sip.left_vel_m_s", self.left_vel_m_s, -0x8000, 0x7FFF),
            MM_S.wire("Sip.right_vel_m_s", self.right_vel_m_s, -0x8000, 0x7FFF),
            DECIVOLT.wire("Sip.battery_v", self.battery_v, 0, 0xFF),
            stall_bumpers, self.control_counts, int(self.flags),
            TWO_DEG.wire("Sip.compass_rad", self.compass_rad, 0, 0xFF),
            len(self.sonar),
        )]
        for k, reading in enumerate(self.sonar):
            name = f"Sip.sonar[{k}]"
            parts.append(_pack(name, _SONAR, reading.number,
                               MM.wire(f"{name}.range_m", reading.range_m, 0, 0xFFFF)))
        for name, st, unit in _TAIL:
            value = getattr(self, name)
            if value is None:
                break
            if isinstance(value, SipIo):
                io_bytes = (getattr(value, f.name) for f in fields(SipIo))
                parts.append(_pack(f"Sip.{name}", st, *io_bytes))
            elif unit is None:
                parts.append(_pack(f"Sip.{name}", st, value))
            else:
                lo, hi = _RANGES[st.format]
                parts.append(_pack(f"Sip.{name}", st, unit.wire(f"Sip.{name}", value, lo, hi)))
        return Packet(int(self.sip_type), b"".join(parts))

    @classmethod
    def from_packet(cls, packet: Packet) -> Sip:
        """Decode a standard SIP. Bytes after the last known group are ignored.

        Raises:
            RemoteProtocolError: the ID is not a SIP type, the packet is shorter than its
                fixed part and sonar readings, or it ends inside an optional group.
        """
        try:
            sip_type = SipType(packet.packet_id)
        except ValueError:
            raise RemoteProtocolError(f"packet 0x{packet.packet_id:02X} is not a SIP") from None
        data = packet.data
        if len(data) < _FIXED.size:
            raise RemoteProtocolError(
                f"SIP of {len(data)} data bytes is shorter than its fixed part ({_FIXED.size})"
            )
        (x, y, th, lvel, rvel, battery, stall_bumpers, control, flags, compass,
         count) = _FIXED.unpack_from(data)
        offset = _FIXED.size
        if len(data) < offset + count * _SONAR.size:
            raise RemoteProtocolError(
                f"SIP SONAR_COUNT {count} needs {count * _SONAR.size} bytes, "
                f"{len(data) - offset} left"
            )
        sonar = []
        for _ in range(count):
            number, range_mm = _SONAR.unpack_from(data, offset)
            sonar.append(SonarReading(number, MM.si(range_mm)))
            offset += _SONAR.size
        tail: dict[str, object] = {}
        for name, st, unit in _TAIL:
            remaining = len(data) - offset
            if remaining <= 0:
                break
            if remaining < st.size:
                raise RemoteProtocolError(
                    f"SIP ends inside {name}: {remaining} byte(s) left, it needs {st.size}"
                )
            values = st.unpack_from(data, offset)
            offset += st.size
            if name == "io":
                tail[name] = SipIo(*values)
            else:
                tail[name] = unit.si(values[0]) if unit else values[0]
        return cls(
            sip_type=sip_type,
            x_counts=x & POSITION_MASK,
            y_counts=y & POSITION_MASK,
            th_counts=th,
            left_vel_m_s=MM_S.si(lvel),
            right_vel_m_s=MM_S.si(rvel),
            battery_v=DECIVOLT.si(battery),
            left_stalled=bool(stall_bumpers & 1),
            right_stalled=bool(stall_bumpers >> 8 & 1),
            rear_bumpers=stall_bumpers >> 1 & 0x7F,
            front_bumpers=stall_bumpers >> 9 & 0x7F,
            control_counts=control,
            flags=SipFlags(flags),
            compass_rad=TWO_DEG.si(compass),
            sonar=tuple(sonar),
            **tail,  # type: ignore[arg-type]
        )


@dataclass(frozen=True, slots=True)
class EncoderPacket:
    """ENCODERpac (ID 0x90): raw wheel encoder counts, sent after each SIP once ENCODER 2.

    Attributes:
        left_counts: left encoder, int32 (ARIA ``processEncoderPacket``, ``bufToByte4``).
        right_counts: right encoder, int32.
    """

    left_counts: int
    right_counts: int

    def to_packet(self) -> Packet:
        return Packet(ENCODER_PACKET_ID, _pack("EncoderPacket", _ENCODER, self.left_counts,
                                            self.right_counts))

    @classmethod
    def from_packet(cls, packet: Packet) -> EncoderPacket:
        """Decode an ENCODERpac.

        Raises:
            RemoteProtocolError: wrong ID or fewer than 8 data bytes.
        """
        if packet.packet_id != ENCODER_PACKET_ID or len(packet.data) < _ENCODER.size:
            raise RemoteProtocolError(
                f"packet 0x{packet.packet_id:02X} with {len(packet.data)} data bytes is not an "
                f"ENCODERpac (0x90, {_ENCODER.size} bytes)"
            )
        return cls(*_ENCODER.unpack_from(packet.data))


def wrap_position(counts: int) -> int:
    """An unbounded position accumulator, counts, as the 15-bit XPOS/YPOS value (mod 0x8000)."""
    return counts & POSITION_MASK


def position_delta(previous_counts: int, current_counts: int) -> int:
    """Signed change between two 15-bit XPOS/YPOS readings, counts, in -0x4000..0x3FFF.

    Unwraps to the nearest representative. ARIA unwraps only changes beyond ±0x1000
    (``processMotorPacket``), so a robot must keep each per-SIP change below 4096
    counts; within that window both rules agree.
    """
    return ((current_counts - previous_counts + 0x4000) & POSITION_MASK) - 0x4000


def _pack(name: str, st: struct.Struct, *values: int) -> bytes:
    try:
        return st.pack(*values)
    except struct.error as e:
        raise LocalProtocolError(f"{name}: {values} does not fit {st.format!r}: {e}") from None


_FIXED = struct.Struct("<HHhhhBHhHBB")
_SONAR = struct.Struct("<BH")
_ENCODER = struct.Struct("<ii")
_TAIL = (
    ("io", struct.Struct("<5B"), None),
    ("real_battery_v", struct.Struct("<H"), DECIVOLT),
    ("charge_state", struct.Struct("<B"), None),
    ("rot_vel_rad_s", struct.Struct("<h"), DECIDEG_S),
    ("fault_flags", struct.Struct("<H"), None),
    ("lat_vel_m_s", struct.Struct("<h"), MM_S),
    ("temperature_c", struct.Struct("<b"), None),
    ("state_of_charge_pct", struct.Struct("<B"), None),
    ("uc_time_us", struct.Struct("<I"), None),
    ("flags3", struct.Struct("<I"), None),
)
_RANGES = {"<H": (0, 0xFFFF), "<h": (-0x8000, 0x7FFF)}
