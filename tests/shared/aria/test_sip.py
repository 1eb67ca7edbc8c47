"""The standard SIP and the ENCODERpac (reference §5)."""

from __future__ import annotations

import math
import re

import pytest
from hypothesis import given

from shared.aria.framing import CorruptPacket, Packet, decode_packet
from shared.aria.sip import (
    ChargeState,
    EncoderPacket,
    Sip,
    SipFlags,
    SipIo,
    SipType,
    SonarReading,
    position_delta,
    wrap_position,
)
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError
from tests.shared.aria.helpers import (
    deframe,
    encoder_packets,
    flip_checksum_byte,
    golden,
    hexbytes,
    random_chunks,
    sips,
)

GOLDEN_SIP = hexbytes(golden()["sip"]["frame"])


@given(sips())
def test_round_trip(sip: Sip) -> None:
    frame = sip.to_packet().to_bytes()
    decoded = Sip.from_packet(decode_packet(frame))
    assert decoded == sip
    assert decoded.to_packet().to_bytes() == frame


def test_golden_sip_field_by_field() -> None:
    sip = Sip.from_packet(decode_packet(GOLDEN_SIP))
    assert sip.sip_type is SipType.MOVING
    assert (sip.x_counts, sip.y_counts, sip.th_counts, sip.control_counts) == (45, 3, 57, 57)
    assert (sip.left_vel_m_s, sip.right_vel_m_s) == (0.099, 0.201)
    assert sip.battery_v == 12.8 and sip.real_battery_v == 12.8
    assert sip.flags == SipFlags(0x1F) and sip.motors_enabled
    assert sip.sonar == tuple(SonarReading(n, 5.0) for n in (12, 13, 14, 15))
    assert sip.io == SipIo() and sip.charge_state == ChargeState.NOT_CHARGING
    assert sip.rot_vel_rad_s == pytest.approx(math.radians(10.0))
    assert sip.fault_flags == 0 and sip.lat_vel_m_s is None  # this SIP ends after FAULTFLAGS
    assert sip.to_packet().to_bytes() == GOLDEN_SIP


def test_random_chunking(rng) -> None:
    golden_sip = Sip.from_packet(decode_packet(GOLDEN_SIP))
    sent = [golden_sip, Sip(), Sip(sip_type=SipType.STOPPED, x_counts=0x7FFF, th_counts=-2048)] * 30
    stream = b"".join(s.to_packet().to_bytes() for s in sent)
    received, buffer = deframe(random_chunks(stream, rng))
    assert [Sip.from_packet(p) for p in received] == sent and buffer.skipped_bytes == 0


@pytest.mark.parametrize("which", [0, 1])
def test_flipped_checksum(which: int, rng) -> None:
    bad = flip_checksum_byte(GOLDEN_SIP, which)
    with pytest.raises(ChecksumError) as info:
        decode_packet(bad)
    assert info.value.expected == 0x42EB
    received, buffer = deframe(random_chunks(GOLDEN_SIP + bad + GOLDEN_SIP, rng))
    assert [type(f) for f in received] == [Packet, CorruptPacket, Packet]
    assert buffer.bad_checksums == 1


def test_classic_sip_ending_after_digout_decodes() -> None:
    # The P2/AROS SIP stops after DIGOUT; ARIA accepts it (reference §5, observed).
    sip = Sip(io=SipIo(digin=0x0F), flags=SipFlags.MOTORS_ENABLED)
    decoded = Sip.from_packet(decode_packet(sip.to_packet().to_bytes()))
    assert decoded.io == SipIo(digin=0x0F) and decoded.real_battery_v is None


def test_truncated_group_or_sonar_is_malformed() -> None:
    data = Sip(io=SipIo(), real_battery_v=12.5).to_packet().data
    with pytest.raises(RemoteProtocolError, match="ends inside real_battery_v: 1 byte"):
        Sip.from_packet(Packet(0x32, data[:-1]))
    with pytest.raises(RemoteProtocolError, match="SONAR_COUNT 2 needs 6 bytes, 3 left"):
        Sip.from_packet(Packet(0x32, Sip().to_packet().data[:-1] + b"\x02\x01\x10\x00"))
    with pytest.raises(RemoteProtocolError, match="shorter than its fixed part"):
        Sip.from_packet(Packet(0x32, b"\x00" * 10))
    with pytest.raises(RemoteProtocolError, match="0x20 is not a SIP"):
        Sip.from_packet(Packet(0x20, GOLDEN_SIP[4:-2]))


def test_position_bit_15_is_ignored_as_aria_does() -> None:
    data = bytearray(Sip(x_counts=5).to_packet().data)
    data[1] |= 0x80
    assert Sip.from_packet(Packet(0x32, bytes(data))).x_counts == 5


def test_stall_and_bumper_bits() -> None:
    sip = Sip(left_stalled=True, right_stalled=True, rear_bumpers=0x05, front_bumpers=0x41)
    assert sip.to_packet().data[11:13] == (1 | 0x05 << 1 | 1 << 8 | 0x41 << 9).to_bytes(2, "little")


def test_invalid_sips_are_refused_with_the_field_named() -> None:
    cases = [
        ({"x_counts": 0x8000}, "Sip.x_counts: 32768 is outside the 15-bit counter"),
        ({"rot_vel_rad_s": 0.1}, "Sip.rot_vel_rad_s is set but the earlier group Sip.io is None"),
        ({"sip_type": 0x40}, "Sip.sip_type: 64 is not a SIP type"),
        ({"front_bumpers": 0x80}, "Sip.front_bumpers: 128 is outside the 7-bit mask"),
    ]
    for change, message in cases:
        with pytest.raises(LocalProtocolError, match=re.escape(message)):
            Sip(**change)
    with pytest.raises(LocalProtocolError, match=re.escape("Sip.left_vel_m_s: 40.0 is 40000 mm/s")):
        Sip(left_vel_m_s=40.0).to_packet()


def test_position_wrap_and_delta() -> None:
    assert wrap_position(-1) == 0x7FFF and wrap_position(0x8000 + 7) == 7
    assert position_delta(32700, wrap_position(32700 + 100)) == 100  # reference §10 wrap case
    assert position_delta(50, 0x7FF0) == -66
    assert position_delta(10, 10) == 0
    assert position_delta(0, 0x3FFF) == 0x3FFF and position_delta(0, 0x4000) == -0x4000


@given(encoder_packets)
def test_encoder_round_trip(packet: EncoderPacket) -> None:
    assert EncoderPacket.from_packet(decode_packet(packet.to_packet().to_bytes())) == packet


def test_encoder_golden_and_chunking(rng) -> None:
    # Layout from reference §5 (ID 0x90, left int32 LE, right int32 LE); checksum worked by
    # hand: 0x9001 + 0x0000 + 0x00FF + 0xFFFF = 0x90FF (mod 2^16), odd byte: ^ 0xFF = 0x9000.
    frame = hexbytes("FA FB 0B 90 01 00 00 00 FF FF FF FF 90 00")
    assert EncoderPacket(1, -1).to_packet().to_bytes() == frame
    received, _ = deframe(random_chunks(frame * 5 + flip_checksum_byte(frame, 0) + frame, rng))
    assert [EncoderPacket.from_packet(p) for p in received if isinstance(p, Packet)] == [
        EncoderPacket(1, -1)] * 6
    with pytest.raises(ChecksumError):
        decode_packet(flip_checksum_byte(frame, 1))
    with pytest.raises(RemoteProtocolError, match="not an ENCODERpac"):
        EncoderPacket.from_packet(Packet(0x90, b"\x00" * 7))
