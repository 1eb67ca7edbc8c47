"""A vehicle endpoint on a real UDP socket, a ground station of our client cores, a FakeApp."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from shared.clock import ManualClock
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
