"""Tests of ``vmnav bench real`` (tools/bench/real.py)."""

from __future__ import annotations

import contextlib
import io
import json

import pytest

from tools.bench.real import TARGETS
from tools.bench.realdata import CATADIOPTRIC_DIR, CATADIOPTRIC_MISSING
from tools.bench.targets import check, targets_of
from tools.cli import main


@pytest.fixture(scope="module")
def result() -> dict:
    """One run's JSON (module-scoped, so capsys cannot be used: it takes seconds)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["bench", "real", "--repeats", "2"]) == 0
    return json.loads(out.getvalue())


def test_the_fisheye_pair_rows(result: dict) -> None:
    assert result["benchmark"] == "real" and result["repeats"] == 2
    pair = result["fisheye_pair"]
    assert pair["reference"]["baseline_m"] == pytest.approx(0.1203, abs=1e-4)
    assert pair["reference"]["rotation_deg"] == pytest.approx(0.2916, abs=1e-4)
    assert pair["paper"]["method"] == "harris-zncc"
    for name in ("paper", "default"):
        row = pair[name]
        assert row["corners_a"] >= row["matches"] >= row["inliers"] > 20 and row["ok"]
        assert row["ms_per_pair_median"] >= row["ms_per_pair_min"] > 0
        assert 0 <= row["rotation_error_deg"] < 180 and 0 <= row["direction_error_deg"] <= 180
    # Every target has its figure; the default front end meets the accuracy ones (the time
    # is the benchmark's verdict: tests run on busy machines).
    checks = {t.figure: check(t, result) for t in targets_of("real")}
    assert set(checks) == set(TARGETS)
    assert all(c.value is not None for c in checks.values())
    for figure in ("fisheye_pair.default.rotation_error_deg",
                   "fisheye_pair.default.direction_error_deg"):
        assert checks[figure].met, checks[figure]


def test_the_equidistant_fits(result: dict) -> None:
    fits = result["equidistant_fit"]
    assert fits["left"]["with_distortion"] is False and fits["left"]["max_px"] < 0.2
    assert fits["right"]["with_distortion"] is True and fits["right"]["max_px"] < 0.05
    assert fits["max_px"] == max(fits["left"]["max_px"], fits["right"]["max_px"])


@pytest.mark.skipif(not CATADIOPTRIC_DIR.is_dir(), reason=CATADIOPTRIC_MISSING)
def test_the_catadioptric_calibration(result: dict) -> None:
    cata = result["catadioptric"]
    assert cata["available"] and (cata["views"], cata["boards_found"]) == (18, 17)
    assert cata["outlier_views"] == ["12.jpg"] and cata["duplicate_views"] == 0
    for figure in ("fx_error_rel", "fy_error_rel", "xi_error"):
        assert check(next(t for t in targets_of("real")
                          if t.figure == f"catadioptric.{figure}"), result).met


def test_bad_repeats(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "real", "--repeats", "0"]) == 1
    assert "--repeats: must be >= 1, got 0" in capsys.readouterr().err
