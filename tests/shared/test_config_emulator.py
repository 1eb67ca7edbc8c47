"""Tests of the emulated Pioneer's table of shared/config.py (``[sim.emulator]``)."""

from __future__ import annotations

import pytest

from shared.config import AriaLinkConfig, EmulatorConfig, VmnavConfig, from_mapping
from shared.errors import ConfigError


def test_defaults_are_an_arcos_robot() -> None:
    config = VmnavConfig().sim.emulator
    assert config == EmulatorConfig()
    assert config.watchdog_stops and config.link == AriaLinkConfig()
    assert config.sonar_max_range_m == 5.0 and config.battery_full_v == 13.0


def test_table_loads_with_its_link() -> None:
    config = from_mapping(VmnavConfig, {"sim": {"emulator": {
        "name": "bench", "watchdog_stops": False, "link": {"watchdog_timeout_ns": 1_000_000_000},
    }}}, "vmnav.toml")
    emulator = config.sim.emulator
    assert (emulator.name, emulator.watchdog_stops) == ("bench", False)
    assert emulator.link.watchdog_timeout_ns == 1_000_000_000


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ({"name": ""}, "sim.emulator: name must be 1-20 printable ASCII"),
        ({"name": "caf\u00e9"}, "name must be 1-20 printable ASCII"),
        ({"battery_empty_v": 14.0}, "battery_empty_v must be in (0, battery_full_v]"),
        ({"battery_full_v": 30.0, "battery_empty_v": 11.0}, "battery_full_v must be < 25.5"),
        ({"sonar_noise_m": -0.1}, "sonar_noise_m must be >= 0"),
        ({"sonar_max_range_m": 70.0}, "sonar_max_range_m must be in (0, 65]"),
        ({"sonar_cycle_ns": 0}, "sonar_cycle_ns must be > 0"),
    ],
)
def test_bad_values_name_the_key(table: dict, fragment: str) -> None:
    with pytest.raises(ConfigError, match=r"vmnav\.toml") as info:
        from_mapping(VmnavConfig, {"sim": {"emulator": table}}, "vmnav.toml")
    assert fragment in str(info.value)
