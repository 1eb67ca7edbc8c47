"""``vmnav bench vision --quick`` on one short taught route (tools/bench/vision.py).

The full run (all lab routes, 300 state and 200 localization queries) is
``vmnav bench vision``; here a 2.5 m route and a dozen queries of each kind.
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import pytest

from robot.config import FeatureConfig
from tests.tools.short_routes import write_short_routes_world
from tools.bench.vision import PAPER_METHOD, TARGETS, target_figures
from tools.cli import main

RATES = ("localize_top1_rate",)
MILLISECONDS = ("frame_ms_median", "frame_ms_p95", "features_ms_median", "state_ms_median",
                "key_segment_ms_median", "localize_ms_300", "localize_ms_3000",
                "localize_exhaustive_ms_300", "localize_exhaustive_ms_3000")
ERRORS = ("y_err_cm_median", "y_err_cm_p90", "y_err_cm_max", "theta_err_deg_median",
          "theta_err_deg_p90", "theta_err_deg_max")


@pytest.fixture(scope="module")
def result(tmp_path_factory: pytest.TempPathFactory) -> dict:
    world = write_short_routes_world(tmp_path_factory.mktemp("world"))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["bench", "vision", "--quick", "--world", str(world), "--routes", "east_a"])
    assert code == 0
    return json.loads(out.getvalue())


@pytest.mark.slow
def test_the_issue_keys_are_there_and_sane(result: dict) -> None:
    assert result["benchmark"] == "vision" and result["routes"] == ["east_a"]
    assert result["image_size"] == [800, 600]
    assert result["frames_timed"] == result["state_queries"] == 12
    assert result["localize_queries"] == 10
    for key in (*RATES, *MILLISECONDS, *ERRORS, "frame_fps_median", "key_images_per_m",
                "localize_speedup_vs_exhaustive"):
        assert isinstance(result[key], float) and math.isfinite(result[key]), key
    assert 0.0 <= result["localize_top1_rate"] <= 1.0
    assert all(result[key] > 0 for key in MILLISECONDS)
    assert result["frame_fps_median"] == pytest.approx(1000.0 / result["frame_ms_median"], rel=0.01)
    assert result["frame_ms_p95"] >= result["frame_ms_median"]
    assert all(result[key] >= 0 for key in ERRORS)
    assert result["y_err_cm_median"] <= result["y_err_cm_p90"] <= result["y_err_cm_max"]
    # The 2.5 m route is cut into a few key images, each with teach tracks.
    assert 1.0 <= result["key_images_per_m"] <= 10.0
    assert result["teach_tracks_per_key_image_median"] > 0


@pytest.mark.slow
def test_failures_are_counted_not_dropped(result: dict) -> None:
    assert 0 <= result["key_pair_not_ok"] <= result["state_not_ok"] <= result["state_queries"]
    split = result["state_by_key_spacing"].values()
    assert sum(part["state_queries"] for part in split) == result["state_queries"]
    assert sum(part["state_not_ok"] for part in split) == result["state_not_ok"]
    direct = result["state_key_pair_matched_directly"]
    assert direct["state_queries"] == result["state_queries"]
    for pairs in result["key_pairs"].values():
        assert 1 <= pairs["key_pairs"] <= result["keyframes"]
        assert 0 <= pairs["key_pairs_not_ok"] <= pairs["key_pairs"]
    tracked = result["key_pairs"]["with_teach_tracks"]
    assert tracked["correspondences_min"] >= result["teach_tracks_per_key_image_median"] / 2


@pytest.mark.slow
def test_both_front_ends_are_measured(result: dict) -> None:
    assert result["front_end"] == FeatureConfig().method
    if result["front_end"] == PAPER_METHOD:
        assert "paper_front_end" not in result
    else:
        paper = result["paper_front_end"]
        assert paper["front_end"] == PAPER_METHOD
        assert paper["state_queries"] == result["state_queries"]
        assert set(paper["targets_met"]) == set(TARGETS)


@pytest.mark.slow
def test_targets_sit_beside_the_figures(result: dict) -> None:
    assert set(result["targets"]) == set(result["targets_met"]) == set(TARGETS)
    assert result["targets"]["frame_fps_median"] == ">= 50"
    assert set(result["versions"]) >= {"python", "numpy", "opencv", "scipy", "poselib"}


def test_target_figures_compare_and_treat_missing_as_not_met() -> None:
    met = target_figures({"frame_fps_median": 50.0, "localize_ms_300": 50.0,
                          "y_err_cm_median": None})["targets_met"]
    assert met["frame_fps_median"] is True
    assert met["localize_ms_300"] is False
    assert met["y_err_cm_median"] is False and met["theta_err_deg_p90"] is False


def test_bad_query_count_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "vision", "--state-queries", "0"]) == 1
    assert "--state-queries: must be >= 1, got 0" in capsys.readouterr().err
