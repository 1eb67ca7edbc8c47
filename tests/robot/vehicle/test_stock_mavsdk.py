"""Stock MAVSDK (the native ``mavsdk`` binding and its bundled ``libcmavsdk``, in-process, as a
ground station) against the vehicle running its own I/O thread on the wall clock:
``first_autopilot``, parameters, ``MissionRaw`` upload, download and start. Effects are checked
on the vehicle's side (FakeApp calls, the parameter file)."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from robot.vehicle.robot_params import ROBOT_PARAMS
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.mavlink.dialect import mavlink, to_float32
from shared.mavlink.mission.goal import GOAL_COMMAND, Goal
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp

_WHY = "mavsdk is not installed (it comes with pip install -e '.[dev]')"
sdk = pytest.importorskip("mavsdk", reason=_WHY)
mission_raw = pytest.importorskip("mavsdk.plugins.mission_raw.mission_raw", reason=_WHY)
param = pytest.importorskip("mavsdk.plugins.param.param", reason=_WHY)

#: How long MAVSDK may take to find the vehicle's autopilot, s (it hears a HEARTBEAT within 1 s).
DISCOVERY_TIMEOUT_S = 5.0
_LEVELS = {sdk.LogLevel.DEBUG: logging.DEBUG, sdk.LogLevel.INFO: logging.INFO,
           sdk.LogLevel.WARN: logging.WARNING, sdk.LogLevel.ERROR: logging.ERROR}
_logger = logging.getLogger("mavsdk")


def _log(level: Any, message: str, file: str | None, line: int) -> bool:
    """MAVSDK's log line into ``logging`` (pytest shows it with a failure), not onto stdout
    from MAVSDK's own threads after pytest stopped capturing."""
    _logger.log(_LEVELS[level], "%s (%s:%d)", message, file, line)
    return True


@pytest.fixture
def autopilot(live_vehicle: UdpVehicle) -> Iterator[Any]:
    """The vehicle as MAVSDK's ``first_autopilot``, MAVSDK configured as a ground station."""
    sdk.log_subscribe(_log)
    mavsdk = sdk.Mavsdk(sdk.Configuration.create_with_component_type(
        sdk.ComponentType.GROUND_STATION))
    try:
        url = f"udpout://127.0.0.1:{live_vehicle.link.local_port}"
        assert mavsdk.add_any_connection(url) == sdk.ConnectionResult.SUCCESS
        system = mavsdk.first_autopilot(DISCOVERY_TIMEOUT_S)
        assert system is not None, f"MAVSDK found no autopilot in {DISCOVERY_TIMEOUT_S} s"
        yield system
    finally:
        mavsdk.destroy()
        sdk.log_unsubscribe()


def goal_item(key_image_id: int) -> Any:
    """A one-goal mission item as MAVSDK's MissionRaw carries it (MISSION_ITEM_INT fields)."""
    return mission_raw.MissionItem(seq=0, frame=mavlink.MAV_FRAME_MISSION, command=GOAL_COMMAND,
                                   current=1, autocontinue=1, param1=float(key_image_id))


def test_first_autopilot_is_a_generic_rover(autopilot: Any) -> None:
    assert autopilot.get_system_id() == 1
    assert autopilot.component_ids() == [1]
    assert autopilot.has_autopilot() and autopilot.is_connected()
    assert autopilot.vehicle_type() == sdk.Vehicle.ROVER
    assert autopilot.autopilot_type() == sdk.Autopilot.GENERIC


def test_params_get_all_get_and_set_are_applied_and_persisted(
        autopilot: Any, app: FakeApp, tmp_path: Path) -> None:
    params = param.Param(autopilot)
    every = params.get_all_params()
    assert sorted(p.name for p in every.float_params) == sorted(b.name for b in ROBOT_PARAMS)
    assert every.int_params == []  # every value REAL32: MAVSDK would decode ints bytewise
    assert params.get_param_float("CTL_SPEED") == to_float32(0.2)

    params.set_param_float("CTL_SPEED", 0.35)
    stored = json.loads((tmp_path / "params.json").read_text())  # written before the echo
    assert stored["params"] == {"CTL_SPEED": to_float32(0.35)}
    assert app.configs[-1].control.speed_m_s == to_float32(0.35)
    assert params.get_param_float("CTL_SPEED") == to_float32(0.35)


def test_param_set_out_of_range_is_refused_once(
        autopilot: Any, app: FakeApp, caplog: pytest.LogCaptureFixture) -> None:
    params = param.Param(autopilot)
    with caplog.at_level(logging.INFO, logger="robot.vehicle.endpoint"):
        with pytest.raises(param.ParamError) as refused:
            params.set_param_float("CTL_SPEED", 5.0)
        # a resent set would reach the vehicle before this read (one socket, in order)
        assert params.get_param_float("CTL_SPEED") == to_float32(0.2)
    assert refused.value.result == param.ParamResult.VALUE_OUT_OF_RANGE
    # PARAM_ERROR before the echo: MAVSDK does not send the set again
    assert sum("ParamRefused" in r.getMessage() for r in caplog.records) == 1
    assert len(app.configs) == 1  # only the config told at construction


def test_mission_raw_upload_download_and_start(autopilot: Any, app: FakeApp) -> None:
    missions = mission_raw.MissionRaw(autopilot)
    missions.upload_mission([goal_item(4)])
    assert app.called("validate_goals") == [((Goal(4),),)]
    (item,) = missions.download_mission()
    assert (item.seq, item.frame, item.command, item.param1) == (
        0, mavlink.MAV_FRAME_MISSION, GOAL_COMMAND, 4.0)

    missions.start_mission()  # DO_SET_MODE in PX4's encoding: AUTO / MISSION
    assert app.called("start_mission") == [((Goal(4),), 0)]
    assert app.state.mode is Mode.AUTO


def test_mission_raw_upload_of_an_unknown_key_image_is_refused(autopilot: Any,
                                                               app: FakeApp) -> None:
    with pytest.raises(mission_raw.MissionRawError) as refused:
        mission_raw.MissionRaw(autopilot).upload_mission([goal_item(99)])
    assert refused.value.result == mission_raw.MissionRawResult.INVALID_ARGUMENT  # INVALID_PARAM1
    assert app.called("validate_goals") == [((Goal(99),),)]
