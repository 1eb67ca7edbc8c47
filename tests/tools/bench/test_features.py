"""Smoke test of tools/bench/features.py (the measurement itself is not a test)."""

from __future__ import annotations

import cv2

from tools.bench.features import bench_features


class TestBenchFeatures:
    def test_smoke(self) -> None:
        threads = cv2.getNumThreads()
        result = bench_features(runs=1, width=320, height=240)
        assert cv2.getNumThreads() == threads
        assert result["runs"] == 1 and result["image_size"] == [320, 240]
        assert set(result) >= {"harris_zncc", "harris_zncc_integer", "orb", "teblid", "beblid",
                               "orb500_bf_crosscheck"}
        harris = result["harris_zncc"]
        assert set(harris) == {"detect_ms", "match_ms", "pair_ms", "matches", "inlier_fraction",
                               "median_error_px"}
        assert harris["matches"] > 20 and harris["inlier_fraction"] > 0.9
        assert result["orb"]["matches"] > 20 and result["orb"]["inlier_fraction"] > 0.8
