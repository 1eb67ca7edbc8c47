"""Tests of the vision components of robot/config/vision.py: FeatureConfig and MatchConfig."""

from __future__ import annotations

import pytest

from robot.config import FeatureConfig, MatchConfig, VmnavConfig
from shared.config import from_mapping
from shared.errors import ConfigError


class TestFeatureConfig:
    def test_defaults_load_from_a_table(self) -> None:
        config = from_mapping(VmnavConfig, {"features": {"max_corners": 500}}, "f.toml")
        assert config.features == FeatureConfig(max_corners=500)
        assert config.matching == MatchConfig()

    @pytest.mark.parametrize(
        ("key", "value", "message"),
        [
            ("method", "surf", "method must be one of harris-zncc, orb, akaze, sift, teblid, "
             "beblid, got 'surf'"),
            ("max_corners", 0, "max_corners must be >= 1, got 0"),
            ("quality_level", 1.0, "quality_level must be in \\(0, 1\\), got 1.0"),
            ("min_distance_deg", -1.0, "min_distance_deg must be >= 0"),
            ("block_size_px", 4, "block_size_px must be odd and >= 3, got 4"),
            ("harris_k", 0.3, "harris_k must be in \\(0, 0.25\\)"),
            ("patch_size_deg", 0.0, "patch_size_deg must be in \\(0, 30\\], got 0.0"),
            ("fast_threshold", 0, "fast_threshold must be in \\[1, 254\\], got 0"),
            ("grid_cells", 0, "grid_cells must be >= 1, got 0"),
            ("descriptor_size_deg", 90.0, "descriptor_size_deg must be in \\(0, 60\\]"),
            ("max_hamming_fraction", 0.6, "max_hamming_fraction must be in \\(0, 0.5\\]"),
            ("subpixel_half_window_px", -1, "subpixel_half_window_px must be >= 0"),
        ],
    )
    def test_invalid_values(self, key: str, value: object, message: str) -> None:
        with pytest.raises(ConfigError, match=f"f.toml: features: {message}"):
            from_mapping(VmnavConfig, {"features": {key: value}}, "f.toml")


class TestMatchConfig:
    def test_none_radius_in_code(self) -> None:
        assert MatchConfig(search_radius_deg=None).search_radius_deg is None

    @pytest.mark.parametrize(
        ("key", "value", "message"),
        [
            ("search_radius_deg", 0.0, "search_radius_deg must be in \\(0, 180\\] or None, "
             "got 0.0"),
            ("ratio_exclusion_deg", -1.0, "ratio_exclusion_deg must be >= 0, got -1.0"),
            ("min_zncc", 1.5, "min_zncc must be in \\[-1, 1\\], got 1.5"),
            ("max_distance_ratio", 0.0, "max_distance_ratio must be in \\(0, 1\\] or None"),
            ("max_distance_ratio", 1.2, "max_distance_ratio must be in \\(0, 1\\] or None"),
        ],
    )
    def test_invalid_values(self, key: str, value: object, message: str) -> None:
        with pytest.raises(ConfigError, match=f"f.toml: matching: {message}"):
            from_mapping(VmnavConfig, {"matching": {key: value}}, "f.toml")
