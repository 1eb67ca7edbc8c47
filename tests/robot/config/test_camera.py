"""CameraSourceConfig (robot/config/devices.py): defaults, TOML tables (with the camera
mount), validation."""

from __future__ import annotations

import pytest

from robot.config import CameraSourceConfig, VmnavConfig
from shared.config import CameraMountConfig, from_mapping
from shared.errors import ConfigError


def test_defaults_and_place_in_the_config_file() -> None:
    config = VmnavConfig().camera
    assert config == CameraSourceConfig()
    assert config.source == "0" and config.max_failed_reads >= 1
    assert config.mount == CameraMountConfig()


def test_from_a_toml_table() -> None:
    config = from_mapping(VmnavConfig, {"camera": {
        "source": "http://127.0.0.1:8080/stream.mjpg", "read_timeout_ns": 2_000_000_000,
    }}, "vmnav.toml")
    assert config.camera.source == "http://127.0.0.1:8080/stream.mjpg"
    assert config.camera.read_timeout_ns == 2_000_000_000
    assert config.camera.mount == CameraMountConfig()


def test_the_mount_is_the_camera_tables_mount_table() -> None:
    config = from_mapping(VmnavConfig, {"camera": {"mount": {"pitch_deg": -5, "x_m": 0.25}}},
                          "vmnav.toml")
    assert config.camera.mount == CameraMountConfig(x_m=0.25, pitch_deg=-5.0)
    assert config.camera.source == CameraSourceConfig().source


@pytest.mark.parametrize(("table", "message"), [
    ({"source": " "}, "source must not be empty"),
    ({"open_timeout_ns": 999_999}, r"open_timeout_ns must be >= 1 ms"),
    ({"read_timeout_ns": 0}, r"read_timeout_ns must be >= 1 ms"),
    ({"max_failed_reads": 0}, "max_failed_reads must be > 0"),
    ({"reconnect_initial_ns": 10, "reconnect_max_ns": 5}, "reconnect_max_ns"),
    ({"source": 0}, "expected a string"),
    ({"mount": {"height_m": 0}}, "height_m must be > 0"),
    ({"mount": {"tilt_deg": 5}}, "unknown key 'tilt_deg'"),
])
def test_bad_values_name_the_key(table: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        from_mapping(VmnavConfig, {"camera": table}, "vmnav.toml")
    assert str(info.value).startswith("vmnav.toml: camera")
