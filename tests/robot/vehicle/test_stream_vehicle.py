"""MAVLink over serial and TCP, both ends our real code: the ground station
(ground/station.py) and the robot's vehicle endpoint on a StreamVehicle, over real TCP
sockets and real pseudo-terminals, in real time (each wait is bounded generously and
ends as soon as its condition holds).

The serial tests join two ptys with a relay (``stream_rig.Radios``), as a pair of SiK
radios joins two serial ports: each end opens its own pty's device path with pyserial,
as it would /dev/ttyUSB0. The relay can also inject what a radio adds (RADIO_STATUS)
and "unplug" the robot's end.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from ground.station import GroundStation
from robot.config import VmnavConfig
from robot.vehicle.vehicle_link import open_vehicle_transport
from shared.byte_link import LinkClosedError
from shared.clock import NS_PER_S, WallClock
from shared.errors import TransportError
from shared.mavlink.dialect import make_codec, mavlink, to_float32
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.stream_rig import UNIX_OFFSET_NS, Radios, start_vehicle

KEY = bytes(range(32))
#: The robot's CTL_SPEED parameter (its default), m/s.
SPEED = to_float32(VmnavConfig().control.speed_m_s)
#: Bound of every wait, s: generous for a loaded machine; the waits end when done.
WAIT_S = 20.0
WAIT_NS = round(WAIT_S * NS_PER_S)


def station(url: str, key: bytes | None = None) -> GroundStation:
    return GroundStation.open(url, WallClock(), key=key, unix_offset_ns=UNIX_OFFSET_NS)


def talk(ground: GroundStation) -> None:
    """The station finds the vehicle and uses three microservices over the link."""
    vehicle = ground.wait_vehicle(WAIT_S)
    assert vehicle.system_id == 1
    assert ground.get_param("CTL_SPEED") == SPEED
    ground.set_mode(Mode.HOLD)
    assert ground.ftp_list("/") is not None


def wait_until(condition: object, what: str) -> None:
    done = threading.Event()
    limit = WallClock().now_ns() + round(WAIT_S * NS_PER_S)
    while not condition() and WallClock().now_ns() < limit:  # type: ignore[operator]
        done.wait(0.02)
    assert condition(), what  # type: ignore[operator]


class TestTcp:
    def test_ground_calls_a_robot_listening_on_tcpin(self, tmp_path: Path) -> None:
        app = FakeApp()
        with start_vehicle(tmp_path, app, "tcpin:127.0.0.1:0") as vehicle:
            port = vehicle.link.local_port  # type: ignore[attr-defined]
            with station(f"tcp:127.0.0.1:{port}") as ground:
                talk(ground)
            assert ("set_mode", Mode.HOLD) in app.calls

    def test_the_robot_calls_a_ground_listening_on_tcpin(self, tmp_path: Path) -> None:
        with station("tcpin:127.0.0.1:0") as ground:
            port = ground.link.local_port
            with start_vehicle(tmp_path, FakeApp(), f"tcp:127.0.0.1:{port}"):
                talk(ground)

    def test_signed_over_tcp(self, tmp_path: Path) -> None:
        app = FakeApp()
        with start_vehicle(tmp_path, app, "tcpin:127.0.0.1:0", key=KEY) as vehicle:
            port = vehicle.link.local_port  # type: ignore[attr-defined]
            with station(f"tcp:127.0.0.1:{port}", key=KEY) as ground:
                talk(ground)
            with station(f"tcp:127.0.0.1:{port}") as unsigned:  # no key: not obeyed
                assert unsigned.run_until(
                    lambda: bool(vehicle.endpoint.stats().unsigned_rejected), WAIT_NS)
                assert app.called("set_mode") == [(Mode.HOLD,)]  # the signed station's only

    def test_a_lost_station_triggers_the_failsafe_and_the_next_one_is_served(
            self, tmp_path: Path) -> None:
        app = FakeApp()
        with start_vehicle(tmp_path, app, "tcpin:127.0.0.1:0", gcs_timeout_s=1.0) as vehicle:
            port = vehicle.link.local_port  # type: ignore[attr-defined]
            with station(f"tcp:127.0.0.1:{port}") as first:
                first.wait_vehicle(WAIT_S)
            wait_until(lambda: app.called("gcs_lost"), "the failsafe after the station left")
            with station(f"tcp:127.0.0.1:{port}") as second:
                talk(second)
            assert app.called("gcs_regained")

    def test_a_second_station_is_refused_while_the_first_talks(self, tmp_path: Path) -> None:
        with start_vehicle(tmp_path, FakeApp(), "tcpin:127.0.0.1:0") as vehicle:
            port = vehicle.link.local_port  # type: ignore[attr-defined]
            with station(f"tcp:127.0.0.1:{port}") as first:
                first.wait_vehicle(WAIT_S)
                with station(f"tcp:127.0.0.1:{port}") as second, \
                        pytest.raises(LinkClosedError, match="closed by the peer"):
                    second.wait_vehicle(WAIT_S)
                assert first.get_param("CTL_SPEED") == SPEED  # still served

    def test_the_ground_reports_a_lost_robot_in_one_line(self, tmp_path: Path) -> None:
        vehicle = start_vehicle(tmp_path, FakeApp(), "tcpin:127.0.0.1:0")
        port = vehicle.link.local_port  # type: ignore[attr-defined]
        with station(f"tcp:127.0.0.1:{port}") as ground:
            ground.wait_vehicle(WAIT_S)
            vehicle.close()
            with pytest.raises(LinkClosedError) as e:
                ground.run_until(lambda: False, round(WAIT_S * NS_PER_S))
        assert str(e.value) == f"tcp:127.0.0.1:{port}: closed by the peer"

    def test_a_robot_calling_an_absent_station_keeps_trying(
            self, tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
        with station("tcpin:127.0.0.1:0") as probe:  # a free port, then nobody there
            port = probe.link.local_port
        with start_vehicle(tmp_path, FakeApp(), f"tcp:127.0.0.1:{port}"):
            wait_until(lambda: "ground link lost" in caplog.text, "a refused connect logged")
            with station(f"tcpin:127.0.0.1:{port}") as ground:  # the station comes up later
                talk(ground)
        lost = [r for r in caplog.records if "ground link lost" in r.getMessage()]
        assert len(lost) == 1 and "Connection refused" in lost[0].getMessage()  # one line


@pytest.fixture
def radios(tmp_path: Path) -> Iterator[Radios]:
    pair = Radios(tmp_path)
    yield pair
    pair.close()


class TestSerial:
    def test_ground_and_robot_over_a_radio_pair(self, tmp_path: Path, radios: Radios) -> None:
        with start_vehicle(tmp_path, FakeApp(), f"serial:{radios.robot_path}:57600"), \
                station(f"serial:{radios.ground_path}:57600") as ground:
            talk(ground)

    def test_pty_addresses(self, tmp_path: Path, radios: Radios) -> None:
        with start_vehicle(tmp_path, FakeApp(), f"pty:{radios.robot_path}"), \
                station(f"pty:{radios.ground_path}") as ground:
            talk(ground)

    def test_signed_with_the_radio_status_the_radio_adds(self, tmp_path: Path,
                                                          radios: Radios) -> None:
        radio = make_codec(51, 68)  # a SiK radio's ids; it never signs
        status = radio.pack(mavlink.MAVLink_radio_status_message(200, 190, 100, 10, 12, 0, 0))
        with start_vehicle(tmp_path, FakeApp(), f"serial:{radios.robot_path}", key=KEY) \
                as vehicle, station(f"serial:{radios.ground_path}", key=KEY) as ground:
            talk(ground)
            before = vehicle.endpoint.stats()
            for _ in range(3):
                radios.inject_to_robot(status)
            wait_until(lambda: vehicle.endpoint.stats().messages >= before.messages + 3,
                       "the robot takes the radio's unsigned RADIO_STATUS")
            stats = vehicle.endpoint.stats()
            assert stats.bad_packets == before.bad_packets
            assert mavlink.MAVLINK_MSG_ID_RADIO_STATUS not in stats.unsigned_rejected
            assert ground.get_param("CTL_SPEED") == SPEED

    def test_an_unplugged_radio_is_opened_again(self, tmp_path: Path, radios: Radios) -> None:
        app = FakeApp()
        with start_vehicle(tmp_path, app, f"serial:{radios.robot_path}", gcs_timeout_s=1.0), \
                station(f"serial:{radios.ground_path}") as ground:
            talk(ground)
            radios.unplug_robot()
            assert ground.run_until(lambda: bool(app.called("gcs_lost")), WAIT_NS)
            radios.plug_robot()
            assert ground.run_until(lambda: bool(app.called("gcs_regained")), WAIT_NS)
            assert ground.get_param("CTL_SPEED") == SPEED

    def test_a_missing_radio_is_an_error_at_start(self, tmp_path: Path) -> None:
        with pytest.raises(TransportError, match="no such device"):
            open_vehicle_transport(f"serial:{tmp_path / 'ttyUSB9'}:57600")
        with pytest.raises(TransportError, match="no such device"):
            station(f"serial:{tmp_path / 'ttyUSB9'}")
