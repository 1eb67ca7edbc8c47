"""The vmnav dialect: generated module in sync with vmnav.xml, codec, VISUAL_SERVO_STATUS."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from robot.mission import MissionState
from shared.errors import InputError
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.generate import MODULE_PATH, generate_dialect
from shared.mavlink.signing import UnsignedPolicy, configure_signing


def test_committed_module_matches_a_fresh_generation(tmp_path: Path) -> None:
    """Fails when vmnav.xml or pymavlink changed: run ``python -m shared.mavlink.generate``."""
    fresh = tmp_path / MODULE_PATH.name
    generate_dialect(fresh)
    assert fresh.read_bytes() == MODULE_PATH.read_bytes()


def test_generation_error_names_the_xml(tmp_path: Path) -> None:
    xml = tmp_path / "broken.xml"
    xml.write_text('<?xml version="1.0"?>\n<mavlink><include>nowhere.xml</include></mavlink>\n')
    with pytest.raises(InputError, match=r"broken\.xml: includes nowhere\.xml, which pymavlink"):
        generate_dialect(tmp_path / "out.py", xml)


def test_mavlink2_is_selected_for_pymavlink() -> None:
    assert os.environ["MAVLINK20"] == "1"
    assert mavlink.WIRE_PROTOCOL_VERSION == "2.0"


def test_visual_servo_status_round_trips() -> None:
    vehicle, ground = make_codec(1, 1), make_codec(255, 190)
    sent = mavlink.MAVLink_visual_servo_status_message(
        time_usec=123_456_789, current_key=41, next_key=42, goal_key=-1, matches=87,
        err_image_max=18.5, err_points=6.25, y=-0.03125, theta=0.015625, s=math.nan,
        state=mavlink.VTR_STATE_FOLLOWING)
    data = vehicle.pack(sent)
    assert data[0] == 0xFD and int.from_bytes(data[7:10], "little") == 24400  # MAVLink 2, 24-bit id
    (got,) = ground.parse(data)
    assert got.get_type() == "VISUAL_SERVO_STATUS"
    assert (got.time_usec, got.current_key, got.next_key, got.goal_key, got.matches) == (
        123_456_789, 41, 42, -1, 87)
    assert (got.err_image_max, got.err_points, got.y, got.theta) == (18.5, 6.25, -0.03125, 0.015625)
    assert math.isnan(got.s) and got.state == mavlink.VTR_STATE_FOLLOWING


def test_vtr_states_name_the_mission_states() -> None:
    names = {e.name for e in mavlink.enums["VTR_STATE"].values()} - {"VTR_STATE_ENUM_END"}
    assert names == {f"VTR_STATE_{s.name}" for s in MissionState} | {"VTR_STATE_TEACHING"}


def test_codec_resyncs_on_garbage_and_counts_corrupt_packets() -> None:
    vehicle, ground = make_codec(1, 1), make_codec(255, 190)
    packets = [vehicle.pack(mavlink.MAVLink_mission_item_reached_message(i)) for i in range(20)]
    corrupt = bytearray(packets[5])
    corrupt[-1] ^= 0xFF
    stream = b"\x00junk" + b"".join(packets[:5]) + bytes(corrupt) + b"".join(packets[6:])
    rng = np.random.default_rng(6)
    cuts = sorted(rng.choice(np.arange(1, len(stream)), size=30, replace=False))
    received = []
    for start, end in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        received += ground.parse(stream[start:end])
    assert [m.seq for m in received] == [i for i in range(20) if i != 5]
    assert [m.get_seq() for m in received][:3] == [0, 1, 2]
    assert ground.bad_packets >= 1


def test_a_datagram_never_leaves_bytes_for_the_next_one() -> None:
    packet = make_codec(1, 1).pack(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3))
    garbage = b"\x00junk\xfd\xff\x00"  # ends like the start of a 255-byte packet
    datagrams = make_codec(255, 190)
    assert datagrams.parse(garbage, datagram=True) == []
    assert [m.get_type() for m in datagrams.parse(packet, datagram=True)] == ["HEARTBEAT"]
    assert datagrams.bad_packets == 2  # the junk, and the packet cut short
    stream = make_codec(255, 190)
    assert stream.parse(garbage) == [] and stream.parse(packet) == []  # a stream waits


def test_only_messages_of_the_dialect_are_verified() -> None:
    packet = bytearray(make_codec(1, 1).pack(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3)))
    packet[7:10] = (0xABCDEF).to_bytes(3, "little")  # an id the dialect lacks: CRC unchecked
    ground = make_codec(255, 190)
    (unknown,) = ground.parse(bytes(packet), datagram=True)
    assert unknown.get_type() == "UNKNOWN_11259375" and not ground.is_verified(unknown)
    (heartbeat,) = ground.parse(make_codec(1, 1).pack(mavlink.MAVLink_heartbeat_message(
        6, 8, 0, 0, 4, 3)), datagram=True)
    assert ground.is_verified(heartbeat)
    assert (ground.unknown_packets, ground.verified_packets, ground.bad_packets) == (1, 1, 0)


def test_on_a_signed_link_only_valid_signatures_are_verified() -> None:
    key = bytes(range(32))
    robot, ground, stranger = make_codec(1, 1), make_codec(255, 190), make_codec(51, 68)
    configure_signing(robot, key, 0, 1_000, UnsignedPolicy([mavlink.MAVLINK_MSG_ID_RADIO_STATUS]))
    configure_signing(ground, key, 1, 1_000)
    (signed,) = robot.parse(ground.pack(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3)))
    radio = mavlink.MAVLink_radio_status_message(200, 190, 100, 10, 5, 0, 0)
    (let_through,) = robot.parse(stranger.pack(radio))  # the policy accepts it unsigned
    assert robot.is_verified(signed) and not robot.is_verified(let_through)
    assert (robot.verified_packets, robot.bad_packets) == (1, 0)
