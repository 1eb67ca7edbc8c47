"""Fuzzing the vehicle endpoint on a signed link (issue 15): a message of any id the
vehicle handles, with any field values, that is unsigned, signed with another key, or
validly signed and then altered anywhere, neither raises nor reaches the application;
it is counted as bad or unknown, never as verified (the count that lets a datagram's
sender become the peer, ``robot.vehicle.udp_vehicle``). An altered packet may still
decode as a message of an id the dialect lacks (pymavlink checks neither CRC nor
signature then): one whose STX 0xFD became 0xFE reads as a MAVLink 1 packet of id 255.

hypothesis picks the message, the way it is spoiled and the seed of its field values
(``vmnav bench fuzz``'s generator, :func:`tools.bench.fuzz_inputs.random_message`).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.signing import configure_signing, timestamp_from_unix_ns
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import UNIX_OFFSET_NS
from tools.bench.fuzz_inputs import random_message
from tools.bench.fuzz_targets import HANDLED_MESSAGES

KEY = bytes(range(32))
OTHER_KEY = bytes(range(1, 33))
#: Everything the vehicle handles but RADIO_STATUS, which a radio may send unsigned.
MESSAGES = [cls for cls in HANDLED_MESSAGES if cls is not mavlink.MAVLink_radio_status_message]


def packed(cls: type, seed: int, key: bytes | None) -> bytes:
    """A ``cls`` message with the field values of ``seed``, from the ground (255/190),
    signed with ``key`` (unsigned when None)."""
    ground = make_codec(255, 190)
    if key is not None:
        configure_signing(ground, key, 0, timestamp_from_unix_ns(UNIX_OFFSET_NS))
    return ground.pack(random_message(cls, np.random.default_rng(seed)))


@settings(derandomize=True, max_examples=200, deadline=None)
@given(cls=st.sampled_from(MESSAGES), seed=st.integers(0, 2**32 - 1),
       spoil=st.sampled_from(["unsigned", "other key", "altered"]),
       at=st.integers(0, 400), flip=st.integers(1, 255))
def test_nothing_without_a_valid_signature_reaches_the_application(
        tmp_path_factory: pytest.TempPathFactory, cls: type, seed: int, spoil: str, at: int,
        flip: int) -> None:
    data = bytearray(packed(cls, seed, {"unsigned": None, "other key": OTHER_KEY}.get(spoil, KEY)))
    if spoil == "altered":
        data[at % len(data)] ^= flip
    app = FakeApp()
    root = tmp_path_factory.mktemp("vehicle")
    endpoint = VehicleEndpoint(app, VmnavConfig(), VehicleFiles(
        root / "memory", root / "upload", root / "params.json"),
        signing=SigningSetup(KEY, UNIX_OFFSET_NS))
    app.calls.clear()

    endpoint.receive(bytes(data), 0, datagram=True)
    endpoint.poll(0)

    codec = endpoint.codec
    assert app.calls == []
    assert codec.verified_packets == 0
    assert codec.bad_packets + codec.unknown_packets >= 1
