"""Robot parameters over real UDP: fetch, set, atomic persistence, reload."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import VehicleFiles
from robot.vehicle.robot_params import ROBOT_PARAMS
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import ManualClock
from shared.errors import ConfigError
from shared.mavlink.dialect import mavlink, to_float32
from shared.mavlink.params.gcs import ParamSetDone, ParamsFetched
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, make_vehicle


def fetch(net: Net) -> dict[str, float]:
    net.ground.send(*net.ground.params.fetch_all(net.now_ns))
    event = net.until_event(net.ground.params)
    assert isinstance(event, ParamsFetched)
    return event.values


def set_param(net: Net, name: str, value: float) -> ParamSetDone:
    net.ground.send(*net.ground.params.set(name, value, net.now_ns))
    event = net.until_event(net.ground.params)
    assert isinstance(event, ParamSetDone)
    return event


def test_fetch_gives_every_parameter_in_index_order(net: Net, app: FakeApp) -> None:
    values = fetch(net)
    assert list(values) == [binding.name for binding in ROBOT_PARAMS]
    assert values["CTL_SPEED"] == to_float32(0.2)
    assert values["FS_GCS_ACTION"] == 0.0  # "hold"
    assert app.configs == [VmnavConfig()]  # the config in force, told at construction


def test_set_is_applied_persisted_atomically_and_reloaded(
        net: Net, app: FakeApp, tmp_path: Path, manual_clock: ManualClock) -> None:
    assert set_param(net, "CTL_SPEED", 0.25) == ParamSetDone("CTL_SPEED", 0.25, 0.25, True)
    assert app.configs[-1].control.speed_m_s == 0.25
    stored = json.loads((tmp_path / "params.json").read_text())
    assert stored == {"format": "vmnav-params", "format_version": 1,
                      "params": {"CTL_SPEED": 0.25}}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params.json", "upload"]  # no temp

    reloaded = FakeApp()
    vehicle = make_vehicle(tmp_path, reloaded, manual_clock)
    second = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    try:
        assert reloaded.configs[0].control.speed_m_s == 0.25
        assert fetch(second)["CTL_SPEED"] == 0.25
    finally:
        second.close()


def test_refused_value_is_echoed_explained_and_not_stored(
        net: Net, app: FakeApp, tmp_path: Path) -> None:
    done = set_param(net, "CTL_SPEED", 5.0)
    assert done == ParamSetDone("CTL_SPEED", 5.0, to_float32(0.2), False)
    net.advance(0.1)
    assert net.ground.notices() == [
        "param CTL_SPEED: 5 is outside [0.01, 1]"]
    assert len(app.configs) == 1 and not (tmp_path / "params.json").exists()


def test_a_set_that_cannot_be_saved_is_reported_and_still_applied(
        tmp_path: Path, manual_clock: ManualClock) -> None:
    app = FakeApp()
    files = VehicleFiles(tmp_path / "memory", tmp_path / "upload",
                         tmp_path / "missing" / "params.json")
    vehicle = UdpVehicle.open("udpin:127.0.0.1:0", VehicleEndpoint(app, VmnavConfig(), files),
                              manual_clock)
    net = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    try:
        assert set_param(net, "CTL_POLE", 0.5).accepted
        net.advance(0.1)
        chunks = net.ground.of_type("STATUSTEXT")  # one notice, longer than 50 characters
        assert {(n.severity, n.id) for n in chunks} == {(mavlink.MAV_SEVERITY_ERROR, 1)}
        assert net.ground.notices() == [
            f"params not saved: {tmp_path}/missing/params.json: cannot write: "
            f"No such file or directory"]
        assert app.configs[-1].control.double_pole == to_float32(0.5)
    finally:
        net.close()


def test_a_broken_parameter_file_stops_construction(tmp_path: Path) -> None:
    (tmp_path / "params.json").write_text('{"format": "vmnav-params", "format_version": 1, '
                                          '"params": {"CTL_SPEED": 9}}')
    files = VehicleFiles(tmp_path / "memory", tmp_path / "upload", tmp_path / "params.json")
    with pytest.raises(ConfigError, match=r"params\.json: params\.CTL_SPEED: 9 is outside"):
        VehicleEndpoint(FakeApp(), VmnavConfig(), files)
