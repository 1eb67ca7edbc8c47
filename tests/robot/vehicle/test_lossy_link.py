"""Mission and parameter protocols between our ground cores and the vehicle through a relay
of two real UDP sockets that drops 20 % of the datagrams each way (issue 6, Checks)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from robot.config import VmnavConfig
from robot.vehicle.robot_params import ROBOT_PARAMS
from shared.clock import ManualClock
from shared.mavlink.dialect import to_float32
from shared.mavlink.mission.gcs import DownloadDone, UploadDone
from shared.mavlink.mission.goal import Goal
from shared.mavlink.params.gcs import ParamSetDone, ParamsFetched
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, Relay, make_vehicle

#: The default retries (10, MavlinkConfig) carry a 25-exchange session through 20 % loss.
CONFIG = VmnavConfig()


@pytest.fixture(params=[11, 12])
def lossy(request: pytest.FixtureRequest, tmp_path: Path, app: FakeApp,
          manual_clock: ManualClock) -> Iterator[tuple[Net, Relay]]:
    vehicle = make_vehicle(tmp_path, app, manual_clock, CONFIG)
    relay = Relay(vehicle.link.local_port, loss=0.2, seed=request.param)
    ground = Ground(f"udpout:127.0.0.1:{relay.port}", config=CONFIG.mavlink)
    net = Net(manual_clock, vehicle, relay, ground)
    yield net, relay
    net.close()


def test_mission_and_parameters_survive_20_percent_loss(
        lossy: tuple[Net, Relay], app: FakeApp) -> None:
    net, relay = lossy
    items = tuple(Goal(key).to_item() for key in (1, 2, 3, 4, 5, 6, 0, 1, 2, 3))
    net.ground.send(*net.ground.mission.upload(items, net.now_ns))
    assert net.until_event(net.ground.mission) == UploadDone(10)
    net.ground.send(*net.ground.mission.download(net.now_ns))
    assert net.until_event(net.ground.mission) == DownloadDone(items)

    net.ground.send(*net.ground.params.fetch_all(net.now_ns))
    fetched = net.until_event(net.ground.params)
    assert isinstance(fetched, ParamsFetched)
    assert list(fetched.values) == [p.name for p in ROBOT_PARAMS]
    net.ground.send(*net.ground.params.set("CTL_SPEED", 0.3, net.now_ns))
    assert net.until_event(net.ground.params) == ParamSetDone(
        "CTL_SPEED", 0.3, to_float32(0.3), True)
    assert app.configs[-1].control.speed_m_s == to_float32(0.3)

    assert app.called("validate_goals")[-1] == (tuple(Goal(k) for k in (1, 2, 3, 4, 5, 6,
                                                                          0, 1, 2, 3)),)
    total = relay.carried + relay.dropped
    assert total > 100 and 0.1 < relay.dropped / total < 0.3
