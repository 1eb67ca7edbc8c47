"""``vmnav log plot`` (tools/figures/log_plot.py): on logs written by LogWriter and by the demo."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from shared.config import LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.logs.writer import LogWriter
from tools.cli import main
from tools.figures.log_plot import PLOT_NAMES, servo_series

MS = 1_000_000
PNG = b"\x89PNG\r\n\x1a\n"


def _write_log(folder: Path, servo: bool = True) -> Path:
    """Five cycles 100 ms apart, driving 0.1 m forward each along a 90 degree heading;
    the third cycle has no estimate (nulls)."""
    with LogWriter(LogConfig(output_dir=str(folder)), "robot") as writer:
        writer.log_text(0, "INFO", "start", "test")
        for i in range(5):
            t_ns = 1_000 * MS + i * 100 * MS
            writer.log_transform(t_ns, [FrameTransform.planar("odom", "base_link", 0.0, 0.1 * i,
                                                              math.pi / 2)])
            if servo:
                estimate = None if i == 2 else 0.01 * i
                writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState", {
                    "stamp_ns": t_ns, "lateral_error_m": estimate, "angular_error_rad": 0.0,
                    "lateral_error_raw_m": estimate, "err_image_max_px": 40.0 - i,
                    "err_points_px": 20.0 - i, "matched_points": 50 + i})
    (path,) = writer.stats().files
    return path


def test_servo_series_distance_from_the_odometry(tmp_path: Path) -> None:
    series = servo_series(_write_log(tmp_path))
    assert series.t_s == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert series.distance_m == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    np.testing.assert_allclose(series.y_m, [0.0, 0.01, np.nan, 0.03, 0.04])
    assert np.isnan(series.theta_raw_rad).all()  # a field the log lacks
    assert series.matches.tolist() == [50, 51, 52, 53, 54]


def test_plot_writes_the_pngs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _write_log(tmp_path)
    assert main(["log", "plot", str(path), "--out", str(tmp_path / "plots")]) == 0
    expected = [tmp_path / "plots" / f"{path.stem}-{name}.png" for name in PLOT_NAMES]
    assert capsys.readouterr().out.splitlines() == [f"wrote {p}" for p in expected]
    assert all(p.read_bytes().startswith(PNG) for p in expected)


def test_a_log_without_servo_state_is_one_line(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    path = _write_log(tmp_path, servo=False)
    assert main(["log", "plot", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert f"{path}: no {topics.SERVO_STATE} messages" in err and topics.TF in err
    assert not list(tmp_path.glob("*.png"))


def test_a_missing_file_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "plot", str(tmp_path / "none.mcap")]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "none.mcap" in err


def test_plot_of_the_demo_log(short_demo, tmp_path: Path) -> None:
    _, out, _ = short_demo
    log = sorted((out / "logs").glob("robot-*.mcap"))[0]
    assert main(["log", "plot", str(log), "--out", str(tmp_path)]) == 0
    assert all((tmp_path / f"{log.stem}-{name}.png").read_bytes().startswith(PNG)
               for name in PLOT_NAMES)
    series = servo_series(log)
    report = json.loads((out / "report.json").read_text())
    assert series.distance_m is not None
    assert series.distance_m[-1] == pytest.approx(report["distance_m"], rel=0.08)
