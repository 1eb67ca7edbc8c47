"""Tests of the route-following tables of robot/config/driving.py (control, estimator,
switching, mission)."""

from __future__ import annotations

import math

import pytest

from robot.config import ControlConfig, EstimatorConfig, MissionConfig, SwitchingConfig, VmnavConfig
from shared.config import from_mapping
from shared.errors import ConfigError


def test_defaults_follow_the_paper_but_for_the_law_and_the_turn_rate() -> None:
    config = VmnavConfig()
    assert config.control == ControlConfig()
    assert (config.control.law, config.control.speed_m_s) == ("paper+ff", 0.2)
    assert config.control.max_omega_rad_s == pytest.approx(math.radians(25))
    assert config.control.double_pole == 0.3
    assert config.switching.err_image_max_px == 20.0
    assert config.estimator == EstimatorConfig() and config.mission == MissionConfig()


def test_tables_load() -> None:
    config = from_mapping(VmnavConfig, {
        "control": {"law": "paper+ff", "double_pole": 1.0, "pole_domain": "distance"},
        "estimator": {"lost_timeout_ns": 3_000_000_000, "gate_chi2": 20},
        "switching": {"hold_frames": 3},
        "mission": {"relocalize_attempts": 4},
    }, "vmnav.toml")
    assert config.control.pole_1_m == 1.0
    assert config.estimator.gate_chi2 == 20.0
    assert config.switching == SwitchingConfig(hold_frames=3)
    assert config.mission.relocalize_attempts == 4


class TestControlConfig:
    @pytest.mark.parametrize(("domain", "pole", "speed", "expected"), [
        ("distance", 0.3, 0.2, 0.3), ("time", 0.3, 0.2, 1.5), ("time", 0.3, 0.5, 0.6),
    ])
    def test_pole_in_distance(self, domain: str, pole: float, speed: float,
                              expected: float) -> None:
        config = ControlConfig(double_pole=pole, pole_domain=domain, speed_m_s=speed)
        assert config.pole_1_m == pytest.approx(expected)


@pytest.mark.parametrize(("table", "values", "message"), [
    ("control", {"law": "pid"}, "law must be one of paper, paper\\+ff"),
    ("control", {"pole_domain": "frequency"}, "pole_domain must be one of distance, time"),
    ("control", {"double_pole": 0}, "double_pole must be > 0"),
    ("control", {"max_omega_rad_s": -1}, "max_omega_rad_s must be > 0"),
    ("estimator", {"sigma_y_m": 0}, "sigma_y_m must be > 0"),
    ("estimator", {"rotation_scale_sigma": -0.1}, "rotation_scale_sigma must be >= 0"),
    ("estimator", {"gate_chi2": 0}, "gate_chi2 must be > 0 or None"),
    ("estimator", {"lost_timeout_ns": 0}, "lost_timeout_ns must be > 0"),
    ("switching", {"err_image_max_px": 0}, "err_image_max_px must be > 0"),
    ("switching", {"pass_margin_m": -0.1}, "pass_margin_m must be >= 0"),
    ("switching", {"hold_frames": 0}, "hold_frames must be >= 1"),
    ("mission", {"localize_attempts": 0}, "localize_attempts must be > 0"),
    ("mission", {"relocalize_timeout_ns": -5}, "relocalize_timeout_ns must be > 0"),
])
def test_bad_values_name_the_table(table: str, values: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        from_mapping(VmnavConfig, {table: values}, "vmnav.toml")
    assert "vmnav.toml" in str(info.value) and table in str(info.value)
