"""CameraSourceConfig (shared/config.py): defaults, TOML table, validation."""

from __future__ import annotations

import pytest

from shared.config import CameraSourceConfig, VmnavConfig, from_mapping
from shared.errors import ConfigError


def test_defaults_and_place_in_the_config_file() -> None:
    config = VmnavConfig().camera
    assert config == CameraSourceConfig()
    assert config.source == "0" and config.max_failed_reads >= 1


def test_from_a_toml_table() -> None:
    config = from_mapping(VmnavConfig, {"camera": {
        "source": "http://127.0.0.1:8080/stream.mjpg", "read_timeout_ns": 2_000_000_000,
    }}, "vmnav.toml")
    assert config.camera.source == "http://127.0.0.1:8080/stream.mjpg"
    assert config.camera.read_timeout_ns == 2_000_000_000


@pytest.mark.parametrize(("table", "message"), [
    ({"source": " "}, "source must not be empty"),
    ({"open_timeout_ns": 999_999}, r"open_timeout_ns must be >= 1 ms"),
    ({"read_timeout_ns": 0}, r"read_timeout_ns must be >= 1 ms"),
    ({"max_failed_reads": 0}, "max_failed_reads must be > 0"),
    ({"reconnect_initial_ns": 10, "reconnect_max_ns": 5}, "reconnect_max_ns"),
    ({"source": 0}, "expected a string"),
])
def test_bad_values_name_the_key(table: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        from_mapping(VmnavConfig, {"camera": table}, "vmnav.toml")
    assert str(info.value).startswith("vmnav.toml: camera")
