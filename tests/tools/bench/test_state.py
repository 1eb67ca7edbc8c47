"""Smoke test of tools/bench/state.py (the measurement itself is not a test)."""

from __future__ import annotations

from tools.bench.state import bench_state


class TestBenchState:
    def test_smoke(self) -> None:
        result = bench_state(runs=3, seed=1)
        assert result["runs"] == 3
        names = ("three_view_previous", "three_view_after_next", "two_view_odometry")
        assert set(result) >= set(names)
        for name in names:
            assert result[name]["ok_rate"] == 1.0
            assert result[name]["y_err_cm_median"] < 5.0
            assert result[name]["state_ms_median"] > 0.0
        assert "key_pair_ms_median" in result["three_view_previous"]
        assert "key_pair_ms_median" not in result["two_view_odometry"]
