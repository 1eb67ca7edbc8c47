from __future__ import annotations

import json

import pytest

from tools.cli import main


def test_bench_sim_prints_json_with_the_figures(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "sim", "--frames", "5"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["benchmark"] == "sim"
    assert result["frames"] == 5
    assert result["render_fps_median"] > 0
    assert result["visible_corners_median"] > 0
    assert result["sensor_ms_median"] > 0 and result["people_in_view_frames"] == 5
    assert result["corner_poses"] == 5 and result["corner_error_px_target"] == 0.5
    assert result["camera_roundtrip_max_px"] < 1e-6
    assert result["camera_roundtrip_max_px_beyond_90deg"] < 1e-6
    assert result["camera_vs_cv2_max_px"] < 1e-6
    assert result["camera_max_angle_deg"] == pytest.approx(92.5, abs=0.05)
