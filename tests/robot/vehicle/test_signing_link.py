"""A signed link over real UDP: signed ground stations work; unsigned, wrongly signed and
replayed packets take no effect and are counted; an unsigned RADIO_STATUS is handled but
does not move the reply address; the vehicle's timestamp keeps up and is kept across a
restart; wrong-key packets cannot lock the real station out."""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from robot.vehicle.udp_vehicle import STRANGER_BUDGET
from shared.clock import ManualClock
from shared.errors import InputError
from shared.mavlink.address import Address
from shared.mavlink.dialect import Message, mavlink, to_float32
from shared.mavlink.mission.gcs import UploadDone
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.mavlink.signing import (
    MAX_TIMESTAMP,
    configure_signing,
    key_from_passphrase,
    signing_stats,
    timestamp_from_unix_ns,
)
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import GCS, UNIX_OFFSET_NS, Ground, Net, make_vehicle

KEY = key_from_passphrase("vmnav signing test")
CUSTOM = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


def signed_ground(net: Net, key: bytes, address: Address, link_id: int,
                  heartbeat: bool = True) -> Ground:
    """A ground station aimed at the vehicle, signing with ``key`` from now on."""
    ground = Ground(f"udpout:127.0.0.1:{net.vehicle.link.local_port}", address, heartbeat)
    configure_signing(ground.codec, key, link_id, timestamp_from_unix_ns(UNIX_OFFSET_NS
                                                                         + net.now_ns))
    return ground


@pytest.fixture
def net(tmp_path: Path, app: FakeApp, manual_clock: ManualClock) -> Iterator[Net]:
    """A signing vehicle, one signed ground station (255, 190)."""
    network = Net(manual_clock, make_vehicle(tmp_path, app, manual_clock, key=KEY))
    network.ends.append(signed_ground(network, KEY, Address(255, 190), link_id=1))
    yield network
    network.close()


def attacks() -> list[Message]:
    """One of each: a mode change, a mission upload, a parameter set, a manual control."""
    return [mavlink.MAVLink_command_long_message(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0,
                                                 CUSTOM, 4, 0, 0, 0, 0, 0),
            mavlink.MAVLink_mission_count_message(1, 1, 1, 0),
            mavlink.MAVLink_param_set_message(1, 1, b"CTL_SPEED", 0.5,
                                              mavlink.MAV_PARAM_TYPE_REAL32),
            mavlink.MAVLink_manual_control_message(1, 500, 0, 0, 0, 0)]


def test_the_signed_ground_station_works(net: Net, app: FakeApp) -> None:
    assert net.command(mavlink.MAV_CMD_DO_SET_MODE, CUSTOM, 4).result == \
        mavlink.MAV_RESULT_ACCEPTED
    net.ground.send(*net.ground.mission.upload((Goal(1).to_item(),), net.now_ns))
    assert net.until_event(net.ground.mission) == UploadDone(1)
    assert app.called("set_mode") == [(Mode.HOLD,)]
    stats = net.vehicle.endpoint.stats()
    assert stats.bad_packets == 0 and stats.unsigned_rejected == {}
    assert stats.signing is not None and stats.signing.good == stats.messages > 0
    ours = signing_stats(net.ground.codec)  # everything the vehicle sent was signed
    assert ours.good == ours.signed > 0 and ours.rejected == 0


def test_unsigned_wrongly_signed_and_replayed_packets_take_no_effect(
        net: Net, app: FakeApp) -> None:
    net.advance(1.5)
    stranger = Ground(f"udpout:127.0.0.1:{net.vehicle.link.local_port}", Address(255, 191),
                      heartbeat=False)
    impostor = signed_ground(net, key_from_passphrase("not the key"), Address(255, 192), 2,
                             heartbeat=False)
    net.ends += [stranger, impostor]
    n = 2  # 8 * n datagrams of strangers: within one round's budget (STRANGER_BUDGET)
    genuine = net.ground.codec.pack(mavlink.MAVLink_manual_control_message(1, 100, 0, 0, 0, 0))
    for _ in range(3):
        net.ground.link.send(genuine)  # the first counts; the copies are replays
    for _ in range(n):  # the last datagrams the vehicle receives in this round
        stranger.send(*attacks())
        impostor.send(*attacks())
    net.advance(2.0)

    assert len(app.called("manual_control")) == 1
    assert app.called("set_mode") == [] and app.called("validate_goals") == []
    assert net.vehicle.endpoint.config.control.speed_m_s == 0.2
    stats = net.vehicle.endpoint.stats()
    assert stats.unsigned_rejected == {mavlink.MAVLINK_MSG_ID_COMMAND_LONG: 2 * n,
                                       mavlink.MAVLINK_MSG_ID_MISSION_COUNT: 2 * n,
                                       mavlink.MAVLINK_MSG_ID_PARAM_SET: 2 * n,
                                       mavlink.MAVLINK_MSG_ID_MANUAL_CONTROL: 2 * n + 2}
    assert stats.signing is not None and stats.signing.rejected == 8 * n + 2
    assert stats.bad_packets == 8 * n + 2
    # Their datagrams did not divert the vehicle's replies from the genuine station.
    assert stranger.datagrams == impostor.datagrams == 0
    assert net.ground.of_type("HEARTBEAT", net.now_ns - 1_000_000_000)


def test_an_unsigned_message_let_through_does_not_divert_the_replies(net: Net) -> None:
    net.advance(0.5)
    radio = Ground(f"udpout:127.0.0.1:{net.vehicle.link.local_port}", Address(51, 68),
                   heartbeat=False)
    net.ends.append(radio)
    radio.send(mavlink.MAVLink_radio_status_message(200, 190, 100, 10, 5, 0, 0))
    sent_ns = net.now_ns
    net.advance(1.0)  # past the vehicle's next HEARTBEAT, which goes out first at 1 s
    stats = net.vehicle.endpoint.stats()
    assert stats.signing is not None and stats.signing.unsigned_accepted == 1  # handled
    assert radio.datagrams == 0
    assert [t for t, m in net.ground.received
            if m.get_type() == "HEARTBEAT" and t > sent_ns] == [1_000_000_000]


def test_the_stations_packets_replayed_from_another_socket_do_not_divert_the_replies(
        net: Net, app: FakeApp) -> None:
    net.advance(1.5)
    captured = net.ground.codec.pack(mavlink.MAVLink_manual_control_message(1, 100, 0, 0, 0, 0))
    net.ground.link.send(captured)
    net.advance(0.5)
    thief = Ground(f"udpout:127.0.0.1:{net.vehicle.link.local_port}", heartbeat=False)
    net.ends.append(thief)
    thief.link.send(captured)
    net.advance(2.0)
    assert len(app.called("manual_control")) == 1
    assert thief.datagrams == 0
    assert net.ground.of_type("HEARTBEAT", net.now_ns - 1_000_000_000)


def test_the_timestamp_keeps_up_with_the_wall_clock(net: Net, app: FakeApp) -> None:
    net.advance(100.0)
    wall = timestamp_from_unix_ns(UNIX_OFFSET_NS + net.now_ns)
    assert net.vehicle.endpoint.codec.signing.timestamp >= wall - 10 * 100_000  # 10 s period
    # A station that starts now accepts the vehicle: its stream is not 60 s old.
    net.ground.heartbeat = False
    late = signed_ground(net, KEY, Address(254, 190), link_id=3)
    net.ends.append(late)
    net.advance(2.0)
    assert late.of_type("HEARTBEAT") and late.codec.bad_packets == 0



def test_wrong_key_packets_spoofing_the_station_do_not_lock_it_out(net: Net, app: FakeApp) -> None:
    # Issue 15: with pymavlink's generated check these 256 packets (the station's
    # address, one per link id, timestamp 2**48-2) shut the real station out until restart.
    # They go out a round's stranger budget at a time, so that every one is parsed.
    net.advance(1.5)
    for link_id in range(256):
        if link_id % STRANGER_BUDGET == 0:
            net.advance(0.05)
        spoof = signed_ground(net, key_from_passphrase("not the key"), GCS, link_id,
                              heartbeat=False)
        spoof.codec.signing.timestamp = MAX_TIMESTAMP - 1
        spoof.send(mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS,
                                                     mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3))
        net.ends.append(spoof)
    net.advance(1.0)
    assert net.command(mavlink.MAV_CMD_DO_SET_MODE, CUSTOM, 4).result == \
        mavlink.MAV_RESULT_ACCEPTED
    assert app.called("set_mode") == [(Mode.HOLD,)]
    stats = net.vehicle.endpoint.stats()
    assert stats.signing is not None and stats.signing.bad == 256


def speed_set(value: float) -> Message:
    return mavlink.MAVLink_param_set_message(1, 1, b"CTL_SPEED", value,
                                             mavlink.MAV_PARAM_TYPE_REAL32)


def test_a_signed_param_set_replayed_after_a_restart_is_refused(
        tmp_path: Path, manual_clock: ManualClock) -> None:
    kept = tmp_path / "signing-timestamps.json"
    first = make_vehicle(tmp_path, FakeApp(), manual_clock, key=KEY, timestamp_file=kept)
    port = first.link.local_port
    net = Net(manual_clock, first)
    ground = signed_ground(net, KEY, GCS, link_id=1, heartbeat=False)
    net.ends.append(ground)
    try:
        captured = ground.codec.pack(speed_set(0.5))  # an eavesdropper keeps a copy
        ground.link.send(captured)
        net.advance(0.5)
        ground.send(speed_set(0.3))
        net.advance(0.5)
        assert first.endpoint.config.control.speed_m_s == to_float32(0.3)
        first.close()  # the robot restarts, on the same socket address
        assert json.loads(kept.read_text())["streams"] == [
            [1, GCS.system_id, GCS.component_id, first.endpoint.codec.signing.stream_timestamps[
                (1, GCS.system_id, GCS.component_id)]]]

        app = FakeApp()
        net.vehicle = make_vehicle(tmp_path, app, manual_clock, key=KEY, timestamp_file=kept,
                                   url=f"udpin:127.0.0.1:{port}")
        ground.link.send(captured)  # the first packet the restarted robot hears
        net.advance(1.0)
        assert net.vehicle.endpoint.config.control.speed_m_s == to_float32(0.3)
        stats = net.vehicle.endpoint.stats()
        assert stats.signing is not None and (stats.signing.bad, stats.messages) == (1, 0)
        ground.send(speed_set(0.4))  # the station itself goes on
        net.advance(0.5)
        assert net.vehicle.endpoint.config.control.speed_m_s == to_float32(0.4)
    finally:
        net.close()


def test_a_broken_or_unwritable_timestamp_file_stops_construction(
        tmp_path: Path, manual_clock: ManualClock) -> None:
    kept = tmp_path / "signing-timestamps.json"
    kept.write_text('{"timestamp": 5, "streams": [[1, 255, 190]]}')
    with pytest.raises(InputError, match=r"signing-timestamps\.json: .*streams\[0\]"):
        make_vehicle(tmp_path, FakeApp(), manual_clock, key=KEY, timestamp_file=kept)
    with pytest.raises(InputError, match=r"missing/t\.json: cannot write"):
        make_vehicle(tmp_path, FakeApp(), manual_clock, key=KEY,
                     timestamp_file=tmp_path / "missing" / "t.json")


def test_timestamps_that_cannot_be_kept_are_reported_once(
        tmp_path: Path, manual_clock: ManualClock) -> None:
    folder = tmp_path / "state"
    folder.mkdir()
    vehicle = make_vehicle(tmp_path, FakeApp(), manual_clock, key=KEY,
                           timestamp_file=folder / "t.json")
    net = Net(manual_clock, vehicle)
    net.ends.append(signed_ground(net, KEY, GCS, link_id=1))
    try:
        net.advance(1.5)
        shutil.rmtree(folder)  # e.g. the disk was unmounted
        net.advance(5.0)
        assert net.ground.notices() == [f"signing timestamps not saved: {folder}/t.json: "
                                        "cannot write: No such file or directory"]
    finally:
        net.close()
