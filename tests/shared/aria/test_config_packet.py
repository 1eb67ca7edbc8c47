"""CONFIGpac 0x20 (reference §6)."""

from __future__ import annotations

import math
import re
from dataclasses import fields, replace

import pytest
from hypothesis import given, settings

from shared.aria.checksum import aria_checksum
from shared.aria.config_packet import ConfigPacket
from shared.aria.framing import CorruptPacket, Packet, decode_packet, encode_packet
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError
from tests.shared.aria.helpers import (
    config_packets,
    deframe,
    flip_checksum_byte,
    golden,
    hexbytes,
    random_chunks,
)


@settings(max_examples=50)
@given(config_packets)
def test_round_trip(config: ConfigPacket) -> None:
    frame = config.to_packet().to_bytes()
    decoded = ConfigPacket.from_packet(decode_packet(frame))
    assert decoded == config
    assert decoded.to_packet().to_bytes() == frame


def test_real_p3dx_sh_prefix() -> None:
    # AriaCoda #15: the first 57 bytes of a real P3DX-SH CONFIGpac (COUNT 0x89). Our copy of
    # the dump stops there, so the prefix is re-framed with its own checksum and decoded
    # with ARIA's rule that fields past the end read as 0.
    posted = hexbytes(golden()["config_p3dx_sh_prefix"]["posted_bytes"])
    assert len(posted) == 57 and posted[:4] == hexbytes("FA FB 89 20")
    config = ConfigPacket.from_packet(decode_packet(encode_packet(0x20, posted[4:])))
    assert (config.robot_class, config.subclass, config.serial_number) == (
        "Pioneer", "p3dx-sh", "GJC_3156")
    assert config.rot_vel_top_rad_s == pytest.approx(math.radians(360))
    assert config.trans_vel_top_m_s == 1.0
    assert config.rot_accel_top_rad_s2 == pytest.approx(math.radians(300))
    assert config.trans_accel_top_m_s2 == 2.0
    assert config.pwm_max == 500 and config.name == "FAPESP_3156"
    assert config.sip_cycle_ns == 100_000_000 and config.host_baud == 0
    assert config.trans_vel_max_m_s == 0.0 and config.high_temperature_shutdown_c == -128


def test_mobilesim_short_packet_and_aria_defaults() -> None:
    # MobileSim stops after PowerbotChargeThreshold; HighTemperatureShutdown then reads -128.
    sent = ConfigPacket(firmware_version="fw-1", high_temperature_shutdown_c=60, gyro_fw_version=3)
    full = sent.to_packet().data
    # firmware version, GyroCW, GyroCCW, KinematicsDelay, 5 x Lat*, PowerbotChargeThreshold
    short = full[: full.index(b"fw-1\0") + len(b"fw-1\0") + 2 + 2 + 1 + 6 * 2]
    config = ConfigPacket.from_packet(Packet(0x20, short))
    assert config.high_temperature_shutdown_c == -128 and config.gyro_fw_version == 0
    assert config.bootloader_version == "" and config.power_bits == 0
    assert config.trans_vel_max_m_s == ConfigPacket().trans_vel_max_m_s


def test_defaults_avoid_the_zero_max_pitfall() -> None:
    # TransVelMax = 0 freezes ARIA's translation (reference §6, observed).
    config = ConfigPacket()
    assert config.trans_vel_max_m_s > 0 and config.rot_vel_max_rad_s > 0
    assert config.sip_cycle_ns == 100_000_000 and config.watchdog_ns == 2_000_000_000
    assert config.auto_baud == 0


def test_random_chunking(rng) -> None:
    sent = [ConfigPacket(), ConfigPacket(name="other", trans_vel_max_m_s=0.75)] * 10
    stream = b"".join(c.to_packet().to_bytes() for c in sent)
    received, _ = deframe(random_chunks(stream, rng, max_chunk=40))
    assert [ConfigPacket.from_packet(p) for p in received] == sent


@pytest.mark.parametrize("which", [0, 1])
def test_flipped_checksum(which: int, rng) -> None:
    frame = ConfigPacket().to_packet().to_bytes()
    bad = flip_checksum_byte(frame, which)
    with pytest.raises(ChecksumError) as info:
        decode_packet(bad)
    assert info.value.expected == aria_checksum(frame[3:-2])
    received, buffer = deframe(random_chunks(bad + frame, rng))
    assert isinstance(received[0], CorruptPacket) and buffer.bad_checksums == 1
    assert ConfigPacket.from_packet(received[-1]) == ConfigPacket()


def test_field_order_follows_aria() -> None:
    names = [f.name for f in fields(ConfigPacket)]
    assert names[:6] == ["robot_class", "subclass", "serial_number", "four_mots",
                         "rot_vel_top_rad_s", "trans_vel_top_m_s"]
    assert names[-3:] == ["bootloader_version", "config_flags", "gyro_fw_version"]
    assert len(names) == 67  # the count of reference §6's list


def test_values_that_do_not_fit_are_named() -> None:
    cases = [
        ({"trans_vel_max_m_s": 70.0}, "ConfigPacket.trans_vel_max_m_s: 70.0 is 70000 mm/s"),
        ({"sip_cycle_ns": 1500}, "ConfigPacket.sip_cycle_ns: 1500 ns is not a whole number"),
        ({"rev_count": 70000}, "ConfigPacket.rev_count: 70000 is outside 0..65535"),
        ({"name": "a\0b"}, "ConfigPacket.name: 'a\\x00b' contains a NUL"),
    ]
    for change, message in cases:
        with pytest.raises(LocalProtocolError, match=re.escape(message)):
            replace(ConfigPacket(), **change).to_packet()
    with pytest.raises(RemoteProtocolError, match="not a CONFIGpac"):
        ConfigPacket.from_packet(Packet(0x21))
