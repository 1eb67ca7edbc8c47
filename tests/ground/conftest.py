"""A real vehicle endpoint (with the tests' FakeApp) on a UDP thread in real time, and the
``vmnav ground`` command line aimed at it."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import WallClock
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle
from tools.cli import main


@pytest.fixture
def app() -> FakeApp:
    return FakeApp()


@pytest.fixture
def vehicle(tmp_path: Path, app: FakeApp) -> Iterator[UdpVehicle]:
    """System 1 listening on an ephemeral 127.0.0.1 port, serviced by its own thread."""
    with make_vehicle(tmp_path, app, WallClock()) as udp_vehicle:
        udp_vehicle.start_thread()
        yield udp_vehicle


def run_ground(vehicle: UdpVehicle, *args: str) -> int:
    """``vmnav ground --connect udpout:<vehicle> SUBCOMMAND...``; the exit code."""
    return main(["ground", "--connect", f"udpout:127.0.0.1:{vehicle.link.local_port}",
                 "--timeout", "3", *args])
