"""SYNC requests and replies (reference §3)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shared.aria.framing import CorruptPacket, Packet, decode_packet
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError
from tests.shared.aria.helpers import (
    deframe,
    flip_checksum_byte,
    golden,
    hexbytes,
    random_chunks,
)

names = st.text(st.characters(min_codepoint=1, max_codepoint=0xFF), max_size=40)


@given(st.builds(RobotIdentity, names, names, names))
def test_identity_round_trip(identity: RobotIdentity) -> None:
    frame = identity.to_packet().to_bytes()
    assert RobotIdentity.from_packet(decode_packet(frame)) == identity


@pytest.mark.parametrize("case", golden()["sync2_replies"], ids=lambda c: c["name"])
def test_golden_sync2_replies(case: dict) -> None:
    identity = RobotIdentity(case["name"], case["robot_class"], case["subclass"])
    assert identity.to_packet().to_bytes() == hexbytes(case["frame"])
    assert RobotIdentity.from_packet(decode_packet(hexbytes(case["frame"]))) == identity


def test_sync_packets_match_reference() -> None:
    for seq, frame in enumerate(("FA FB 03 00 00 00", "FA FB 03 01 00 01", "FA FB 03 02 00 02")):
        assert SyncRequest(seq).to_packet().to_bytes() == hexbytes(frame)
    assert SyncReply(1).to_packet() == SyncRequest(1).to_packet()


def test_random_chunking_and_flipped_checksum(rng) -> None:
    frame = RobotIdentity().to_packet().to_bytes()
    with pytest.raises(ChecksumError):
        decode_packet(flip_checksum_byte(frame, 0))
    stream = frame + flip_checksum_byte(frame, 1) + frame
    received, buffer = deframe(random_chunks(stream, rng, max_chunk=4))
    assert [type(f) for f in received] == [Packet, CorruptPacket, Packet]
    assert RobotIdentity.from_packet(received[2]) == RobotIdentity() and buffer.bad_checksums == 1


def test_malformed_identity() -> None:
    with pytest.raises(RemoteProtocolError, match="not three NUL-terminated strings"):
        RobotIdentity.from_packet(Packet(2, b"vmnav\0Pioneer\0"))
    with pytest.raises(RemoteProtocolError, match="not three NUL-terminated strings"):
        RobotIdentity.from_packet(Packet(2, b"a\0b\0c"))
    with pytest.raises(RemoteProtocolError, match="has ID 1, not 2"):
        RobotIdentity.from_packet(Packet(1, b"a\0b\0c\0"))


def test_invalid_values_are_refused() -> None:
    with pytest.raises(LocalProtocolError, match="seq must be 0, 1 or 2, got 3"):
        SyncRequest(3)
    with pytest.raises(LocalProtocolError, match="RobotIdentity answers SYNC2"):
        SyncReply(2)
    with pytest.raises(LocalProtocolError, match=r"RobotIdentity\.subclass: .* outside Latin-1"):
        RobotIdentity(subclass="p3at-\u263a")
