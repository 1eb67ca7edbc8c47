"""MAVLink over serial and TCP, both ends our real code: the ground station
(ground/station.py) and the robot's vehicle endpoint on a StreamVehicle, over real TCP
sockets and real pseudo-terminals, in real time (each wait is bounded generously and
ends as soon as its condition holds).

The serial tests join two ptys with a relay, as a pair of SiK radios joins two serial
ports: each end opens its own pty's device path with pyserial, as it would
/dev/ttyUSB0. The relay can also inject what a radio adds (RADIO_STATUS) and "unplug"
the robot's end.
"""

from __future__ import annotations

import dataclasses
import os
import select
import threading
import tty
from collections.abc import Iterator
from pathlib import Path

import pytest

from ground.station import GroundStation
from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.vehicle_io import VehicleIo
from robot.vehicle.vehicle_link import open_vehicle_transport, vehicle_on
from shared.byte_link import LinkClosedError
from shared.clock import NS_PER_S, WallClock
from shared.errors import TransportError
from shared.mavlink.dialect import make_codec, mavlink, to_float32
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp

KEY = bytes(range(32))
UNIX_OFFSET_NS = 1_750_000_000 * NS_PER_S
#: The robot's CTL_SPEED parameter (its default), m/s.
SPEED = to_float32(VmnavConfig().control.speed_m_s)
#: Bound of every wait, s: generous for a loaded machine; the waits end when done.
WAIT_S = 20.0
WAIT_NS = round(WAIT_S * NS_PER_S)


def start_vehicle(root: Path, app: FakeApp, url: str, *, key: bytes | None = None,
                  gcs_timeout_s: float = 5.0) -> VehicleIo:
    """System 1 on ``url`` (FakeApp), serviced by its own thread."""
    config = VmnavConfig()
    config = dataclasses.replace(config, mavlink=dataclasses.replace(
        config.mavlink, gcs_timeout_ns=round(gcs_timeout_s * NS_PER_S)))
    files = VehicleFiles(root / "memory", root / "upload", root / "params.json")
    signing = SigningSetup(key, UNIX_OFFSET_NS) if key is not None else None
    endpoint = VehicleEndpoint(app, config, files, signing=signing)
    vehicle = vehicle_on(open_vehicle_transport(url), endpoint, WallClock())
    vehicle.start_thread()
    return vehicle


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


class Radios:
    """Two ptys joined by a relay thread: what one end writes, the other reads.

    The robot's end is reached through a symlink (``robot_path``), so that it can be
    unplugged (its pty closed, the link removed) and plugged in again (a new pty).
    """

    def __init__(self, root: Path) -> None:
        self.robot_path = root / "robot-radio"
        self._lock = threading.Lock()
        self._robot = self._new_pty(self.robot_path)
        self._ground = self._new_pty(root / "ground-radio")
        self.ground_path = root / "ground-radio"
        self._inject = b""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._relay, daemon=True)
        self._thread.start()

    @staticmethod
    def _new_pty(link: Path) -> tuple[int, int]:
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        link.unlink(missing_ok=True)
        link.symlink_to(os.ttyname(slave))
        return master, slave

    def inject_to_robot(self, data: bytes) -> None:
        """Bytes the robot's radio adds to what it delivers (RADIO_STATUS)."""
        with self._lock:
            self._inject += data

    def unplug_robot(self) -> None:
        with self._lock:
            for fd in self._robot:
                os.close(fd)
            self._robot = (-1, -1)
            self.robot_path.unlink()

    def plug_robot(self) -> None:
        with self._lock:
            self._robot = self._new_pty(self.robot_path)

    def _relay(self) -> None:
        while not self._stop.is_set():
            with self._lock:  # unplugging waits at most one select
                robot, ground = self._robot[0], self._ground[0]
                if self._inject and robot >= 0:
                    os.write(robot, self._inject)
                    self._inject = b""
                fds = [fd for fd in (robot, ground) if fd >= 0]
                for source in select.select(fds, [], [], 0.01)[0]:
                    target = ground if source == robot else robot
                    try:
                        data = os.read(source, 4096)
                        if target >= 0:
                            os.write(target, data)
                    except OSError:
                        pass  # a full buffer on the other side: lost, as on a radio link

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        for fd in (*self._robot, *self._ground):
            if fd >= 0:
                os.close(fd)


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
