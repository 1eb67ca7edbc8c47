"""LogConfig: defaults, the [log] table, and its limits."""

from __future__ import annotations

import pytest

from robot.config import VmnavConfig
from shared.config import LogConfig, from_mapping
from shared.errors import ConfigError


def test_defaults_flush_within_a_second() -> None:
    config = VmnavConfig().log
    assert config == LogConfig()
    assert 0 < config.flush_period_ns <= 1_000_000_000
    assert (config.frame_rate_hz, config.compression) == (15.0, "lz4")


def test_log_table_is_read() -> None:
    config = from_mapping(VmnavConfig, {"log": {"output_dir": "runs", "jpeg_quality": 70,
                                                "rotate_size_bytes": 500_000_000}}, "vmnav.toml")
    assert (config.log.output_dir, config.log.jpeg_quality,
            config.log.rotate_size_bytes) == ("runs", 70, 500_000_000)


@pytest.mark.parametrize(("table", "fragment"), [
    ({"flush_period_ns": 2_000_000_000}, "flush_period_ns must be <= 1 s"),
    ({"compression": "gzip"}, "compression must be one of none, lz4, zstd, got 'gzip'"),
    ({"jpeg_quality": 0}, "jpeg_quality must be in 1..100, got 0"),
    ({"queue_messages": 0}, "queue_messages must be > 0, got 0"),
    ({"output_dir": " "}, "output_dir must not be empty"),
])
def test_bad_values_name_the_key(table: dict, fragment: str) -> None:
    with pytest.raises(ConfigError) as error:
        from_mapping(VmnavConfig, {"log": table}, "vmnav.toml")
    assert str(error.value).startswith("vmnav.toml: log: ") and fragment in str(error.value)
