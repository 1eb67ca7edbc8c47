"""PioneerDriverConfig (robot/config/devices.py): defaults, TOML tables, validation."""

from __future__ import annotations

import pytest

from robot.config import PioneerDriverConfig, VmnavConfig
from shared.config import AriaLinkConfig, from_mapping
from shared.errors import ConfigError


def test_defaults_and_place_in_the_config_file() -> None:
    config = VmnavConfig().pioneer
    assert config == PioneerDriverConfig()
    assert config.baud == 38400 and config.link == AriaLinkConfig()
    assert config.max_speed_m_s > 0 and config.max_omega_rad_s > 0  # ref §6: never 0


def test_from_a_toml_table() -> None:
    config = from_mapping(VmnavConfig, {"pioneer": {
        "url": "socket://robot.local:8101", "link": {"link_timeout_ns": 2_000_000_000},
    }}, "vmnav.toml")
    assert config.pioneer.url == "socket://robot.local:8101"
    assert config.pioneer.link.link_timeout_ns == 2_000_000_000


@pytest.mark.parametrize(("table", "message"), [
    ({"url": " "}, "url must not be empty"),
    ({"baud": 0}, "baud must be > 0"),
    ({"command_timeout_ns": 0}, "command_timeout_ns must be > 0"),
    ({"reconnect_initial_ns": 10, "reconnect_max_ns": 5}, "reconnect_max_ns"),
    ({"max_speed_m_s": 0.0}, "max_speed_m_s must be > 0"),
    ({"link": {"sync_attempts": 0}}, "sync_attempts must be >= 1"),
])
def test_bad_values_name_the_key(table: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        from_mapping(VmnavConfig, {"pioneer": table}, "vmnav.toml")
    assert str(info.value).startswith("vmnav.toml: pioneer")
