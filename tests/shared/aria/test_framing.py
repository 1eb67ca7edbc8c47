"""Framing: encode/decode, the resyncing PacketBuffer (reference §1)."""

from __future__ import annotations

import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shared.aria.framing import (
    MAX_DATA_LEN,
    CorruptPacket,
    Packet,
    PacketBuffer,
    decode_packet,
    encode_packet,
)
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError
from tests.shared.aria.helpers import (
    deframe,
    flip_checksum_byte,
    golden,
    hexbytes,
    random_chunks,
)

packets = st.builds(Packet, st.integers(0, 255), st.binary(max_size=MAX_DATA_LEN))


@given(packets)
def test_round_trip(packet: Packet) -> None:
    frame = packet.to_bytes()
    assert frame[2] == len(packet.data) + 3
    assert decode_packet(frame) == packet


@pytest.mark.parametrize("case", golden()["checksums"], ids=lambda c: c["name"])
def test_golden_frames(case: dict) -> None:
    body = hexbytes(case["body"])
    assert encode_packet(body[0], body[1:]) == hexbytes(case["frame"])
    assert decode_packet(hexbytes(case["frame"])) == Packet(body[0], body[1:])


def test_random_chunking_recovers_every_packet(rng) -> None:
    sent = [Packet(int(rng.integers(0, 256)), rng.bytes(int(rng.integers(0, 120))))
            for _ in range(200)]
    stream = b"".join(p.to_bytes() for p in sent)
    received, buffer = deframe(random_chunks(stream, rng))
    assert received == sent
    assert buffer.bad_checksums == 0 and buffer.skipped_bytes == 0 and buffer.pending_bytes == 0


@pytest.mark.parametrize("which", [0, 1])
def test_flipped_checksum_byte(which: int) -> None:
    frame = Packet(0x0B, b"\x3b\xc8\x00").to_bytes()
    bad = flip_checksum_byte(frame, which)
    with pytest.raises(ChecksumError) as info:
        decode_packet(bad)
    assert (info.value.expected, info.value.actual) == (0xD33B, int.from_bytes(bad[-2:], "big"))


def test_flipped_checksum_is_counted_and_skipped_in_a_stream(rng) -> None:
    sent = [Packet(n, bytes([n]) * n) for n in range(1, 30)]
    frames = [p.to_bytes() for p in sent]
    frames[10] = flip_checksum_byte(frames[10], 1)
    received, buffer = deframe(random_chunks(b"".join(frames), rng))
    corrupt = [f for f in received if isinstance(f, CorruptPacket)]
    assert len(corrupt) == 1 and corrupt[0].frame == frames[10] and corrupt[0].packet_id == 11
    assert [f for f in received if isinstance(f, Packet)] == sent[:10] + sent[11:]
    assert buffer.bad_checksums == 1


def test_wms2_and_garbage_before_sync_are_skipped(rng) -> None:
    wms2 = hexbytes(golden()["wms2"]["bytes"])
    sync0 = hexbytes("FA FB 03 00 00 00")
    noise = bytes(b for b in rng.bytes(200) if b != 0xFA)
    received, buffer = deframe(random_chunks(wms2 + sync0 + noise + sync0, rng, max_chunk=3))
    assert received == [Packet(0), Packet(0)]
    assert buffer.skipped_bytes == len(wms2) + len(noise)


def test_lone_fa_fb_in_garbage_resyncs() -> None:
    # FA FB followed by COUNT 2 cannot start a frame; FA FA FB must still find the SYNC.
    good = Packet(4, b"\x3b\x01\x00").to_bytes()
    received, buffer = deframe([b"\xfa\xfb\x02" + b"\xfa" + good])
    assert received == [Packet(4, b"\x3b\x01\x00")]
    assert buffer.skipped_bytes == 4


def test_dropped_byte_does_not_cost_the_next_frame() -> None:
    first = Packet(0x33, bytes(range(40))).to_bytes()
    second = Packet(0x20, b"config").to_bytes()
    damaged = first[:20] + first[21:]  # one byte lost inside the first frame
    buffer = PacketBuffer()
    buffer.feed(damaged + second)
    frames = []
    while (frame := buffer.next_frame()) is not None:
        frames.append(frame)
    assert frames[-1] == Packet(0x20, b"config")
    assert all(isinstance(f, CorruptPacket) for f in frames[:-1])


def test_count_above_127_is_unsigned() -> None:
    # ARIA before 2025 read COUNT as a signed char and dropped these (AriaCoda #15).
    packet = Packet(0x20, bytes(200))
    assert packet.to_bytes()[2] == 203
    assert deframe([packet.to_bytes()])[0] == [packet]


def test_partial_frame_waits_then_can_be_abandoned() -> None:
    good = Packet(0x32, b"sip").to_bytes()
    buffer = PacketBuffer()
    buffer.feed(b"\xfa\xfb\xf0" + b"junk" + good)  # a spurious header claims 240 bytes
    assert buffer.next_frame() is None and buffer.pending_bytes > 0
    buffer.abandon_partial()
    assert buffer.next_frame() == Packet(0x32, b"sip")
    assert buffer.abandoned_frames == 1 and buffer.pending_bytes == 0


def test_trailing_fa_is_kept_for_the_next_chunk() -> None:
    buffer = PacketBuffer()
    buffer.feed(b"xx\xfa")
    assert buffer.next_frame() is None and buffer.pending_bytes == 1
    buffer.feed(Packet(1).to_bytes()[1:])
    assert buffer.next_frame() == Packet(1)


@pytest.mark.parametrize(
    ("frame", "problem"),
    [
        (b"\xfa\xfb\x03\x00\x00", "shorter than the minimum 6"),
        (b"\xfb\xfa\x03\x00\x00\x00", "not FA FB"),
        (b"\xfa\xfb\x02\x00\x00\x00", "below the minimum 3"),
        (b"\xfa\xfb\x04\x00\x00\x00", "says 4 bytes follow it, but 3 do"),
    ],
)
def test_malformed_single_frame(frame: bytes, problem: str) -> None:
    with pytest.raises(RemoteProtocolError, match=problem):
        decode_packet(frame)


def test_too_long_or_bad_id_is_refused() -> None:
    with pytest.raises(LocalProtocolError, match="253 data bytes exceed the 252"):
        encode_packet(1, bytes(MAX_DATA_LEN + 1))
    with pytest.raises(LocalProtocolError, match=re.escape("outside 0..255")):
        Packet(256)
