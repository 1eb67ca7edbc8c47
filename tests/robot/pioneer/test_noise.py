"""Garbage, partial headers and corrupt SIPs on the line never crash the driver and are counted."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.pioneer.events import LinkNoise
from robot.pioneer.status import LinkState
from tests.robot.pioneer.responder import Rig
from tests.shared.aria.helpers import flip_checksum_byte

junk = st.one_of(
    st.binary(max_size=40),
    st.sampled_from([b"\xfa", b"\xfa\xfb", b"\xfa\xfb\x02", b"\xfa\xfb\x09\x32",
                     b"\xfa\xfb\xff", b"WMS2\r"]),
)
gaps = st.lists(junk, max_size=3).map(b"".join)
sips = st.lists(st.tuples(gaps, st.integers(-500, 500), st.booleans()), min_size=1, max_size=8)


@settings(max_examples=40, deadline=None)
@given(sips)
def test_noise_between_sips(plan: list[tuple[bytes, int, bool]]) -> None:
    rig = Rig()
    rig.connect()
    robot = rig.responder
    robot.send_sips = False  # the test writes the SIPs itself, with noise around them
    rig.events()
    garbage = corrupted = 0
    for gap, step_counts, corrupt in [*plan, (b"", 0, False)]:  # a clean SIP ends the run
        robot.x_counts += step_counts
        frame = robot.session.send(robot.sip(), rig.clock.now_ns())
        if corrupt:
            frame = flip_checksum_byte(frame, 1)
            corrupted += 1
        robot.link.write(gap + frame)
        garbage += len(gap)
        rig.run(0.1)
    rig.run(1.0)  # past the frame timeout (a partial header lets go) and the noise report
    counters = rig.driver.counters()
    assert rig.driver.status().link is LinkState.CONNECTED
    assert rig.driver.state().odom_pose[0] == pytest.approx(robot.x_counts / 1000)
    assert counters.bad_checksums >= corrupted
    assert counters.skipped_bytes >= garbage
    if not corrupted:
        assert counters.skipped_bytes == garbage
    noise = [e for e in rig.events() if isinstance(e, LinkNoise)]
    assert sum(e.skipped_bytes for e in noise) == counters.skipped_bytes
    assert bool(noise) == bool(garbage or corrupted)
