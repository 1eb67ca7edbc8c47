"""GroundStation against real vehicle endpoints over loopback UDP: several vehicles, goal
outcomes, signing, keyboard driving, garbage datagrams."""

from __future__ import annotations

import dataclasses
import math
import select
from collections.abc import Iterator
from pathlib import Path

import pytest

from ground.station import STRANGER_BUDGET, GroundError, GroundStation
from ground.teleop import drive
from robot.config import VmnavConfig
from robot.mission import MissionState
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import ManualClock, WallClock
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.udp_link import UdpLink
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import UNIX_OFFSET_NS, make_vehicle

KEY = bytes(range(32))


@pytest.fixture
def station(vehicle: UdpVehicle) -> Iterator[GroundStation]:
    """A station aimed at the conftest's vehicle, which it has heard."""
    with GroundStation.open(f"udpout:127.0.0.1:{vehicle.link.local_port}",
                            WallClock()) as ground:
        ground.wait_vehicle(3.0)
        yield ground


def system_config(system_id: int) -> VmnavConfig:
    config = VmnavConfig()
    return dataclasses.replace(config, mavlink=dataclasses.replace(config.mavlink,
                                                                   system_id=system_id))


def test_listening_station_picks_a_vehicle_by_system_id(tmp_path: Path) -> None:
    clock = WallClock()
    apps = {1: FakeApp(), 2: FakeApp()}
    with GroundStation.open("udpin:127.0.0.1:0", clock, system_id=2) as station:
        url = f"udpout:127.0.0.1:{station.link.local_port}"
        with (make_vehicle(tmp_path / "1", apps[1], clock, system_config(1), url=url) as one,
              make_vehicle(tmp_path / "2", apps[2], clock, system_config(2), url=url) as two):
            one.start_thread()
            two.start_thread()
            assert station.wait_vehicle(3.0).system_id == 2
            assert station.set_param("CTL_SPEED", 0.5) == pytest.approx(0.5)
            station.set_mode(Mode.HOLD)
            station.run_until(lambda: len(station.fleet.vehicles) == 2, 2_000_000_000)
    assert apps[2].configs[-1].control.speed_m_s == pytest.approx(0.5)
    assert apps[1].configs[-1].control.speed_m_s != pytest.approx(0.5)
    assert apps[2].called("set_mode") == [(Mode.HOLD,)] and apps[1].called("set_mode") == []
    assert sorted(station.fleet.vehicles) == [1, 2]


def test_garbage_in_one_datagram_does_not_swallow_the_next(tmp_path: Path,
                                                            manual_clock: ManualClock) -> None:
    with GroundStation.open("udpin:127.0.0.1:0", WallClock()) as station:
        url = f"udpout:127.0.0.1:{station.link.local_port}"
        with (UdpLink.open(url) as noise,
              make_vehicle(tmp_path, FakeApp(), manual_clock, url=url) as vehicle):
            noise.send(b"\xfd\xff\x00" + bytes(range(40)))  # starts a 255-byte packet
            vehicle.service(0)  # its first HEARTBEAT, and no other until 1 s (never here)
            assert station.wait_vehicle(0.5).system_id == 1
    assert station.codec.bad_packets == 1  # the garbage, cut short by its datagram's end


def test_a_flood_of_strangers_does_not_hide_the_vehicle(tmp_path: Path,
                                                        manual_clock: ManualClock) -> None:
    with GroundStation.open("udpin:127.0.0.1:0", WallClock()) as station:
        url = f"udpout:127.0.0.1:{station.link.local_port}"
        with (UdpLink.open(url) as noise,
              make_vehicle(tmp_path, FakeApp(), manual_clock, url=url) as vehicle):
            vehicle.service(0)
            first_ns = station.wait_vehicle(0.5).last_heartbeat_ns
            for i in range(300):  # more than one old 256-datagram read
                noise.send(b"\xfd\x09garbage" + i.to_bytes(4, "little"))
            manual_clock.sleep_until_ns(1_000_000_000)
            vehicle.service(manual_clock.now_ns())  # its second HEARTBEAT, after the flood
            assert select.select([station.link], [], [], 1.0)[0]
            station.service()  # one round
            assert station.fleet.vehicles[1].last_heartbeat_ns > first_ns
    assert (station.codec.bad_packets, station.shed) == (STRANGER_BUDGET, 300 - STRANGER_BUDGET)


def test_only_verified_packets_reach_the_taps(tmp_path: Path, manual_clock: ManualClock) -> None:
    tapped: list[str] = []
    with GroundStation.open("udpin:127.0.0.1:0", WallClock()) as station:
        station.packet_taps.append(lambda way, packet, msg, t_ns: tapped.append(
            f"{way} {msg.get_type()}"))
        url = f"udpout:127.0.0.1:{station.link.local_port}"
        with (UdpLink.open(url) as stranger,
              make_vehicle(tmp_path, FakeApp(), manual_clock, url=url) as vehicle):
            # A well-framed packet of an id the dialect lacks: it decodes, unverified.
            stranger.send(bytes([0xFD, 4, 0, 0, 0, 42, 1, 0xEF, 0xCD, 0xAB]) + bytes(6))
            vehicle.service(0)
            station.wait_vehicle(0.5)
    assert station.codec.unknown_packets == 1
    assert "in HEARTBEAT" in tapped and not [t for t in tapped if "UNKNOWN" in t]


def test_wait_mission_done_from_telemetry(station: GroundStation, app: FakeApp) -> None:
    station.upload_goals([Goal(2), Goal(5)])
    station.start_mission()
    assert app.called("start_mission") == [((Goal(2), Goal(5)), 0)]
    assert not station.wait_mission_done(0.2)  # still localizing
    app.update(mission_state=MissionState.FOLLOWING, reached_seqs=(0,), mission_seq=1)
    assert not station.wait_mission_done(0.2)  # item 0 is not the last
    app.update(mission_state=MissionState.ARRIVED, reached_seqs=(0, 1))
    assert station.wait_mission_done(2.0)


def test_a_run_stopped_short_is_not_reached(station: GroundStation, app: FakeApp) -> None:
    station.upload_goals([Goal(2)])
    station.start_mission()
    app.update(mission_state=MissionState.ABORTED, mission_detail="bumper")
    assert not station.wait_mission_done(2.0)
    assert station.mission_outcome is False
    assert station.vehicle is not None and station.vehicle.notices[-1] == "mission aborted: bumper"


def test_refused_mode_is_an_error_with_the_result(station: GroundStation) -> None:
    with pytest.raises(GroundError, match="answered MAV_CMD_DO_SET_MODE with MAV_RESULT_DENIED"):
        station.set_mode(Mode.AUTO)  # no mission uploaded


def test_signed_link(tmp_path: Path) -> None:
    clock = WallClock()
    with make_vehicle(tmp_path, FakeApp(), clock, key=KEY) as vehicle:
        vehicle.start_thread()
        url = f"udpout:127.0.0.1:{vehicle.link.local_port}"
        with GroundStation.open(url, clock, key=KEY, unix_offset_ns=UNIX_OFFSET_NS) as signed:
            signed.wait_vehicle(3.0)
            assert signed.get_param("CTL_SPEED") == pytest.approx(0.2)
        with (GroundStation.open(url, clock) as unsigned,
              pytest.raises(GroundError, match=r"no HEARTBEAT from a vehicle within 0\.3 s")):
            unsigned.wait_vehicle(0.3)
        assert vehicle.endpoint.stats().unsigned_rejected


def test_drive_sends_the_held_command(station: GroundStation, app: FakeApp) -> None:
    keys = iter(["w", "", "wwd", "", "a ", "", "q"])
    drive(station, lambda: next(keys), station.clock, period_ns=20_000_000)

    def sent() -> list[tuple[float, float]]:
        return [(x, r) for x, y, z, r, *_ in app.called("manual_control")]

    station.run_until(lambda: len(sent()) == 7, 2_000_000_000)
    assert sent() == [(0.2, 0.0), (0.2, 0.0), (0.6, 0.2), (0.6, 0.2), (0.0, 0.0), (0.0, 0.0),
                      (0.0, 0.0)]
    assert all(math.isnan(y) and math.isnan(z) for _, y, z, *_ in app.called("manual_control"))
