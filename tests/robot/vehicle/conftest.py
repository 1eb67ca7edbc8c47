"""A vehicle endpoint on a real UDP socket, a ground station of our client cores, a FakeApp;
or the vehicle alone on the wall clock, for stock ground stations."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import ManualClock, WallClock
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, make_vehicle


@pytest.fixture
def app() -> FakeApp:
    return FakeApp()


@pytest.fixture
def net(tmp_path: Path, app: FakeApp, manual_clock: ManualClock) -> Iterator[Net]:
    """The vehicle (udpin, ephemeral port) and one ground station aimed at it."""
    vehicle = make_vehicle(tmp_path, app, manual_clock)
    network = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    yield network
    network.close()


@pytest.fixture
def live_vehicle(tmp_path: Path, app: FakeApp) -> Iterator[UdpVehicle]:
    """The vehicle (udpin, ephemeral port, files under ``tmp_path``) running its own I/O
    thread on the wall clock, as on the robot."""
    vehicle = make_vehicle(tmp_path, app, WallClock())
    vehicle.start_thread()
    yield vehicle
    vehicle.close()
