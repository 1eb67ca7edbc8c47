"""Tests of the relative-pose and path-state tables of robot/config/vision.py."""

from __future__ import annotations

import pytest

from robot.config import PathStateConfig, RelativePoseConfig, VmnavConfig
from shared.config import from_mapping
from shared.errors import ConfigError


def test_defaults_and_nested_tables() -> None:
    config = from_mapping(VmnavConfig, {"path_state": {
        "min_points": 4, "relative_pose": {"model": "planar", "inlier_threshold_rad": 0.01},
    }}, "vmnav.toml")
    assert config.path_state.min_points == 4
    assert config.path_state.relative_pose.model == "planar"
    assert config.path_state.pose_before_resection.refine_passes == 1
    assert PathStateConfig().relative_pose == RelativePoseConfig()


def test_matching_window_is_wide_and_configurable() -> None:
    assert PathStateConfig().matching.search_radius_deg == pytest.approx(39.57, abs=0.01)
    config = from_mapping(VmnavConfig, {"path_state": {"matching": {"search_radius_deg": 25.0}}},
                          "vmnav.toml")
    assert config.path_state.matching.search_radius_deg == 25.0
    assert config.path_state.matching.min_zncc == PathStateConfig().matching.min_zncc


@pytest.mark.parametrize(("table", "message"), [
    ({"relative_pose": {"model": "homography"}}, "model must be one of planar, general, auto"),
    ({"relative_pose": {"huber_scale_rad": 0.1}}, "huber_scale_rad must be in"),
    ({"relative_pose": {"refine_passes": -1}}, "refine_passes must be >= 0"),
    ({"min_points": 1}, "min_points must be >= 2"),
    ({"max_odometry_disagreement_deg": 0.0}, "max_odometry_disagreement_deg"),
])
def test_bad_values_name_the_table(table: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        from_mapping(VmnavConfig, {"path_state": table}, "vmnav.toml")
    assert "vmnav.toml" in str(info.value) and "path_state" in str(info.value)
