"""Fuzzing the host end of the ARIA link (issue 15): whatever a robot sends after the
handshake, :class:`~robot.pioneer.client.PioneerClient` and the ``shared.aria`` decoders
behind its session never raise, nor do the client's command, timers and status after them.

The harness is ``vmnav bench fuzz``'s ``aria_host`` target (connect a fresh client, feed
the bytes, command, run its timers); hypothesis makes the bytes: the robot's own packets
(CONFIG, SIPs, ENCODER, identity) with bytes edited and the checksum made valid again,
so they reach the decoders, packets of any id, and raw noise.
"""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from shared.aria.framing import MAX_DATA_LEN, encode_packet
from tools.bench.fuzz_targets import AriaHostTarget

TARGET = AriaHostTarget(Path("."))  # builds nothing on disk
#: Packet ids a robot sends: sync replies and identity, CONFIG, SIPs, ENCODER, resets.
ROBOT_IDS = (0, 1, 2, 0x20, 0x32, 0x33, 0x90, 0xFE, 0xFF)


@st.composite
def edited_packet(draw: st.DrawFn) -> tuple[int, bytes]:
    """One of the robot's valid packets with a few bytes overwritten, inserted or cut."""
    packet_id, data = draw(st.sampled_from([*TARGET.packets, TARGET.identity]))
    buf = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(buf)))
        value = draw(st.sampled_from((0x00, 0x01, 0x7F, 0x80, 0xFF)) | st.integers(0, 255))
        op = draw(st.sampled_from("sid"))
        if op == "s" and at < len(buf):
            buf[at] = value
        elif op == "i":
            buf[at:at] = bytes((value,))
        else:
            del buf[at:at + value % 8 + 1]
    return packet_id, bytes(buf[:MAX_DATA_LEN])


any_packet = st.tuples(st.sampled_from(ROBOT_IDS) | st.integers(0, 255),
                       st.binary(max_size=MAX_DATA_LEN))
stream = st.lists(st.one_of(edited_packet(), any_packet).map(lambda p: encode_packet(*p))
                  | st.binary(min_size=1, max_size=40), min_size=1, max_size=8).map(b"".join)


@settings(derandomize=True, max_examples=400, deadline=None)
@given(stream)
def test_no_robot_byte_stream_makes_the_client_raise(data: bytes) -> None:
    TARGET.run(data)
