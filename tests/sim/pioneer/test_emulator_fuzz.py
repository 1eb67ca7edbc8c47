"""Fuzzing the robot end of the ARIA link (issue 15): whatever a connected client sends,
the emulated Pioneer (``sim.pioneer.emulator``) never raises, through the next SIP cycle.

The harness is ``vmnav bench fuzz``'s ``aria_robot`` target (a new session on one
simulation: connect, the bytes, one SIP period of simulation); hypothesis makes the
bytes: commands of every number with boundary int arguments, string arguments, SYNCs,
packets of any id, and raw noise.
"""

from __future__ import annotations

from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from shared.aria import Command
from shared.aria.commands import ArgType
from shared.aria.framing import MAX_DATA_LEN, encode_packet
from tools.bench.fuzz_targets import AriaRobotTarget

TARGET = AriaRobotTarget(Path("."))  # builds nothing on disk

int_arg = st.builds(lambda sign, magnitude: bytes((sign,)) + magnitude.to_bytes(2, "little"),
                    st.sampled_from((ArgType.INT, ArgType.NEG_INT)),
                    st.sampled_from((0, 1, 255, 256, 0x7FFF, 0x8000, 0xFFFF))
                    | st.integers(0, 0xFFFF))
str_arg = st.binary(max_size=40).map(lambda text: bytes((ArgType.STR, len(text))) + text)
command = st.tuples(st.sampled_from([int(c) for c in Command]),
                    int_arg | str_arg | st.just(b""))
any_packet = st.tuples(st.integers(0, 255), st.binary(max_size=MAX_DATA_LEN))
stream = st.lists(st.one_of(command, any_packet).map(lambda p: encode_packet(*p))
                  | st.binary(min_size=1, max_size=40), min_size=1, max_size=8).map(b"".join)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(stream)
def test_no_client_byte_stream_makes_the_emulator_raise(data: bytes) -> None:
    TARGET.run(data)
