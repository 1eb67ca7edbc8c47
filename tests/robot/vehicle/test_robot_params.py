"""The robot's parameters: declared from VmnavConfig, and a PARAM_SET changes the config."""

from __future__ import annotations

import dataclasses

import pytest

from robot.config import ControlConfig, VmnavConfig
from robot.vehicle.robot_params import (
    ROBOT_PARAMS,
    config_with_params,
    param_problem,
    robot_param_table,
)
from shared.config import MavlinkConfig
from shared.errors import ConfigError
from shared.mavlink.params.gcs import ParamClient
from shared.mavlink.params.table import NAME_LEN
from shared.mavlink.params.vehicle import ParamChanged, ParamRefused, ParamServer
from tests.shared.mavlink.link import GCS, VEHICLE, Endpoint, Link, events


def test_defaults_come_from_the_config() -> None:
    config = VmnavConfig(control=ControlConfig(speed_m_s=0.3, law="paper+ff"),
                         mavlink=MavlinkConfig(gcs_lost_action="continue"))
    table = robot_param_table(config)
    values = table.values()
    assert values["CTL_SPEED"] == 0.3
    assert values["CTL_LAW"] == 1.0 and values["FS_GCS_ACTION"] == 1.0
    assert values["SW_ERR_IMG_MAX"] == config.switching.err_image_max_px
    assert values["EST_LOST_TMO"] == 2.0 and values["MIS_LOC_TMO"] == 30.0
    assert values["MIS_RELOC_TRIES"] == 10.0
    assert len(values) == len(ROBOT_PARAMS)
    assert all(len(spec.name) <= NAME_LEN for spec in table)
    assert table.spec_of("FS_GCS_ACTION").description.endswith("(0 hold, 1 continue)")
    assert config_with_params(config, table) == config  # nothing set: nothing changes


def test_set_values_map_back_to_config_fields() -> None:
    config = VmnavConfig()
    table = robot_param_table(config)
    for name, value in (("CTL_SPEED", 0.25), ("CTL_MAX_OMEGA", 0.3), ("CTL_LAW", 1),
                        ("SW_ERR_IMG_MAX", 12.5), ("EST_LOST_TMO", 3.5), ("MIS_LOC_TRIES", 7),
                        ("MIS_RELOC_TMO", 45.0), ("FS_GCS_ACTION", 1)):
        table.set(name, value)
    new = config_with_params(config, table)
    assert (new.control.speed_m_s, new.control.max_omega_rad_s, new.control.law) == (
        0.25, 0.3, "paper+ff")
    assert new.switching.err_image_max_px == 12.5
    assert new.estimator.lost_timeout_ns == 3_500_000_000
    assert (new.mission.localize_attempts, new.mission.relocalize_timeout_ns) == (
        7, 45_000_000_000)
    assert new.mavlink.gcs_lost_action == "continue"
    assert new.control.double_pole == config.control.double_pole
    assert new.matching == config.matching


def test_config_outside_a_parameter_range_is_refused() -> None:
    config = VmnavConfig(control=ControlConfig(speed_m_s=3.0))
    with pytest.raises(ConfigError, match=r"CTL_SPEED: default 3 is outside \[0.01, 1\]"):
        robot_param_table(config)


def test_param_set_over_the_link_changes_the_config_the_robot_uses() -> None:
    config = VmnavConfig()
    table = robot_param_table(config)
    client, server = ParamClient(GCS, VEHICLE), ParamServer(table, VEHICLE)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE, server))
    link.send(link.ground, client.set("SW_ERR_IMG_MAX", 15.0, 0))
    link.run(lambda: client.operation is None)
    (changed,) = events(server)
    assert isinstance(changed, ParamChanged) and changed.name == "SW_ERR_IMG_MAX"
    config = config_with_params(config, table)
    assert config.switching.err_image_max_px == 15.0
    assert config == dataclasses.replace(
        VmnavConfig(), switching=dataclasses.replace(VmnavConfig().switching,
                                                     err_image_max_px=15.0))


def test_a_value_that_contradicts_another_parameter_is_refused_with_param_error() -> None:
    config = VmnavConfig()
    table = robot_param_table(config)
    client = ParamClient(GCS, VEHICLE)
    server = ParamServer(table, VEHICLE,
                         check=lambda name, value: param_problem(config, table, name, value))
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE, server))
    link.send(link.ground, client.set("SAFE_SLOW_DIST", 0.3, 0))  # below SAFE_STOP_DIST 0.4
    link.run(lambda: client.operation is None)
    (refused,) = events(server)
    assert isinstance(refused, ParamRefused) and refused.name == "SAFE_SLOW_DIST"
    assert "slow_distance_m must be > stop_distance_m" in refused.reason
    assert table.value("SAFE_SLOW_DIST") == pytest.approx(1.2)
    assert param_problem(config, table, "SAFE_SLOW_DIST", 2.0) is None


def test_the_safety_layer_has_no_off_switch_among_the_parameters() -> None:
    assert not [b for b in ROBOT_PARAMS if b.section == "safety" and b.field == "enabled"]
