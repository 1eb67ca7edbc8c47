"""CONFIGpac (ID 0x20), the robot's reply to the CONFIG command (reference §6).

The fields follow in the order ARIA reads them (``ArRobotConfigPacketReader.cpp:84-190``):
strings are NUL-terminated, integers little-endian. Each field of
:class:`ConfigPacket` carries its wire format in its metadata, so the dataclass is
the single description of the layout.

Reading rules, as ARIA's: a short packet is fine; fields past its end read as 0 or
as an empty string, except HighTemperatureShutdown, which reads as -128 when absent
(MobileSim stops after PowerbotChargeThreshold). Encoding always writes every field.

Pitfall (reference §6, observed): a reply with ``trans_vel_max_m_s == 0`` (or
``rot_vel_max_rad_s == 0``) leaves ARIA's maximum at 0 and the robot never
translates (or rotates). The defaults below are non-zero. A full packet has COUNT
>= 128, which ARIA before 2025 drops; it then falls back to its parameter files.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field, fields
from typing import Any

from shared.aria._wire import (
    DECIVOLT,
    DEG_S,
    DEG_S2,
    MM_S,
    MM_S2,
    NS_PER_MS,
    TEXT_ENCODING,
    WireUnit,
    encode_cstring,
)
from shared.aria.framing import Packet
from shared.errors import LocalProtocolError, RemoteProtocolError

CONFIG_PACKET_ID = 0x20
_STR = "z"  # pseudo struct format: NUL-terminated string
_MS = "ms"  # pseudo unit: milliseconds on the wire, integer ns above
_ABSENT_TEMPERATURE = -128


def _f(fmt: str, default: Any, unit: WireUnit | str | None = None) -> Any:
    """A field with its wire format (struct code or ``"z"``) and unit in the metadata."""
    return field(default=default, metadata={"fmt": fmt, "unit": unit})


@dataclass(frozen=True, slots=True)
class ConfigPacket:
    """CONFIGpac contents in SI units. Defaults: a P3-AT-SH emulator's reply.

    Tops and PWM come from a real P3DX-SH (AriaCoda #15); the current maxima and
    accelerations from MobileSim's p3at model (0.6 m/s, 0.75 rad/s, accel 0.3 / decel
    0.6 m/s², 1.74 rad/s²), rounded to whole wire units; the rest as MobileSim sends.

    Raises:
        LocalProtocolError: from :meth:`to_packet` when a value does not fit its field.
    """

    robot_class: str = _f(_STR, "Pioneer")
    subclass: str = _f(_STR, "p3at-sh")
    serial_number: str = _f(_STR, "SIM")
    """Serial number; "SIM" makes ARIA treat the robot as a simulator (no MTX connectors)."""
    four_mots: int = _f("B", 0)
    """Unused (once: an AT with P2OS); ARIA skips it."""
    rot_vel_top_rad_s: float = _f("H", math.radians(360), DEG_S)
    trans_vel_top_m_s: float = _f("H", 1.0, MM_S)
    rot_accel_top_rad_s2: float = _f("H", math.radians(300), DEG_S2)
    trans_accel_top_m_s2: float = _f("H", 2.0, MM_S2)
    pwm_max: int = _f("H", 500)
    name: str = _f(_STR, "vmnav")
    sip_cycle_ns: int = _f("B", 100 * NS_PER_MS, _MS)
    """SIP period, ns (u8 ms)."""
    host_baud: int = _f("B", 0)
    """Baud code 0-4: 9600/19200/38400/57600/115200."""
    aux1_baud: int = _f("B", 0)
    has_gripper: int = _f("H", 0)
    front_sonar: int = _f("H", 1)
    rear_sonar: int = _f("B", 1)
    low_battery_v: float = _f("H", 0.0, DECIVOLT)
    rev_count: int = _f("H", 0)
    watchdog_ns: int = _f("H", 2000 * NS_PER_MS, _MS)
    """ARCOS watchdog, ns (u16 ms)."""
    normal_mpacs: int = _f("B", 0)
    stall_val: int = _f("H", 0)
    stall_count: int = _f("H", 0)
    joy_vel_m_s: float = _f("H", 0.0, MM_S)
    joy_rot_vel_rad_s: float = _f("H", 0.0, DEG_S)
    rot_vel_max_rad_s: float = _f("H", math.radians(43), DEG_S)
    trans_vel_max_m_s: float = _f("H", 0.6, MM_S)
    rot_accel_rad_s2: float = _f("H", math.radians(100), DEG_S2)
    rot_decel_rad_s2: float = _f("H", math.radians(100), DEG_S2)
    rot_kp: int = _f("H", 0)
    rot_kv: int = _f("H", 0)
    rot_ki: int = _f("H", 0)
    trans_accel_m_s2: float = _f("H", 0.3, MM_S2)
    trans_decel_m_s2: float = _f("H", 0.6, MM_S2)
    trans_kp: int = _f("H", 0)
    trans_kv: int = _f("H", 0)
    trans_ki: int = _f("H", 0)
    front_bumps: int = _f("B", 0)
    rear_bumps: int = _f("B", 0)
    has_charger: int = _f("B", 0)
    sonar_cycle: int = _f("B", 0)
    auto_baud: int = _f("B", 0)
    """2 lets ARIA send HOSTBAUD on serial links."""
    gyro_type: int = _f("B", 0)
    drift_factor: int = _f("h", 0)
    aux2_baud: int = _f("B", 0)
    aux3_baud: int = _f("B", 0)
    ticks_mm: int = _f("H", 0)
    shutdown_voltage_v: float = _f("H", 0.0, DECIVOLT)
    firmware_version: str = _f(_STR, "vmnav")
    gyro_cw: int = _f("H", 0)
    gyro_ccw: int = _f("H", 0)
    kinematics_delay: int = _f("B", 0)
    lat_vel_top_m_s: float = _f("H", 0.0, MM_S)
    lat_accel_top_m_s2: float = _f("H", 0.0, MM_S2)
    lat_vel_max_m_s: float = _f("H", 0.0, MM_S)
    lat_accel_m_s2: float = _f("H", 0.0, MM_S2)
    lat_decel_m_s2: float = _f("H", 0.0, MM_S2)
    powerbot_charge_threshold: int = _f("H", 0)
    pdb_port: int = _f("B", 0)
    gyro_rate_limit: int = _f("H", 0)
    high_temperature_shutdown_c: int = _f("b", _ABSENT_TEMPERATURE)
    """degC; -128 = none (and what a packet without the field decodes to)."""
    power_bits: int = _f("H", 0)
    battery_type: int = _f("B", 0)
    soc_low_pct: int = _f("H", 0)
    soc_shutdown_pct: int = _f("H", 0)
    bootloader_version: str = _f(_STR, "")
    config_flags: int = _f("I", 0)
    gyro_fw_version: int = _f("h", 0)

    def to_packet(self) -> Packet:
        """Encode every field.

        Raises:
            LocalProtocolError: a value does not fit its field (message names it).
        """
        parts = []
        for field_name, st, unit in _LAYOUT:
            name, value = f"ConfigPacket.{field_name}", getattr(self, field_name)
            if st is None:
                parts.append(encode_cstring(name, value))
                continue
            lo, hi = _range(st)
            if unit == _MS:
                if value % NS_PER_MS:
                    raise LocalProtocolError(f"{name}: {value} ns is not a whole number of ms")
                wire = value // NS_PER_MS
            elif isinstance(unit, WireUnit):
                wire = unit.wire(name, value, lo, hi)
            else:
                wire = value
            if not lo <= wire <= hi:
                raise LocalProtocolError(f"{name}: {wire} is outside {lo}..{hi} on the wire")
            parts.append(st.pack(wire))
        return Packet(CONFIG_PACKET_ID, b"".join(parts))

    @classmethod
    def from_packet(cls, packet: Packet) -> ConfigPacket:
        """Decode a CONFIGpac with ARIA's rules for short packets.

        Raises:
            RemoteProtocolError: the ID is not 0x20.
        """
        if packet.packet_id != CONFIG_PACKET_ID:
            raise RemoteProtocolError(f"packet 0x{packet.packet_id:02X} is not a CONFIGpac (0x20)")
        data, offset = packet.data, 0
        values: dict[str, Any] = {}
        for name, st, unit in _LAYOUT:
            if st is None:
                end = data.find(b"\0", offset)
                end = len(data) if end < 0 else end
                values[name] = data[offset:end].decode(TEXT_ENCODING)
                offset = end + 1
                continue
            if len(data) - offset >= st.size:
                (wire,) = st.unpack_from(data, offset)
            elif name == "high_temperature_shutdown_c" and offset >= len(data):
                wire = _ABSENT_TEMPERATURE
            else:
                wire = 0  # ARIA's bufTo*() past the end
            offset += st.size
            if unit == _MS:
                values[name] = wire * NS_PER_MS
            elif isinstance(unit, WireUnit):
                values[name] = unit.si(wire)
            else:
                values[name] = wire
        return cls(**values)


_LAYOUT: tuple[tuple[str, struct.Struct | None, WireUnit | str | None], ...] = tuple(
    (f.name, None if f.metadata["fmt"] == _STR else struct.Struct("<" + f.metadata["fmt"]),
     f.metadata["unit"])
    for f in fields(ConfigPacket)
)
"""(field name, struct or None for a C string, unit) in wire order."""


def _range(st: struct.Struct) -> tuple[int, int]:
    bits = 8 * st.size
    if st.format[-1].islower():
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return 0, (1 << bits) - 1
