"""A hostile robot end: well-framed packets with fuzzed contents never raise in the driver,
and a sane robot afterwards is driven again."""

from __future__ import annotations

import contextlib

from hypothesis import given, settings
from hypothesis import strategies as st

from robot.pioneer.status import LinkState
from shared.aria import encode_packet
from shared.byte_link import LinkClosedError
from tests.robot.pioneer.responder import Rig

ROBOT_IDS = [0x32, 0x33, 0x34, 0x20, 0x90, 0x00, 0x01, 0x02, 0xF0, 0x62]
"""SIP types, CONFIG, ENCODER, the handshake replies and packets the codec leaves raw."""

PACKETS = st.tuples(
    st.one_of(st.sampled_from(ROBOT_IDS), st.integers(0, 0xFF)),
    st.one_of(st.binary(max_size=30), st.binary(min_size=20, max_size=252)),
).map(lambda p: encode_packet(*p))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(PACKETS, min_size=1, max_size=30))
def test_fuzzed_robot_packets_never_raise(packets: list[bytes]) -> None:
    rig = Rig()
    rig.connect()
    rig.responder.send_sips = False  # only the fuzz speaks for a while
    for packet in packets:
        link = rig.responder.link  # None, or closed, after a reset notice until the reopen
        if link is not None:
            with contextlib.suppress(LinkClosedError):
                link.write(packet)
        rig.step()
    rig.responder.send_sips = True
    rig.run(0.5)  # a reset notice (0xFE, 0xFF) in the fuzz makes the driver reconnect
    rig.run_until(lambda: rig.driver.status().link is LinkState.CONNECTED)
    assert rig.driver.counters().sips > 0
