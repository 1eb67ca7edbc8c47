"""``vmnav calibrate --capture``: views picked from a real video source (an MJPEG AVI of
rendered board views read by cv2.VideoCapture), then calibrated."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.calibration_capture import GRID, CaptureGoal, ViewPicker
from shared.calibration import read_camera
from shared.camera_model import CameraModel
from shared.chessboard import Chessboard
from tests.tools.board_video import board_video, render_board_views, write_video
from tools.cli import main

#: The camera behind the video: the default lens with some distortion.
TRUTH = CameraModel(
    800, 600, CameraModel.default().K, 1.6, np.array([-0.05, 0.01, 0.001, -0.0005]), 185.0
)
BOARD = Chessboard(9, 6, 0.025)


@pytest.fixture(scope="module")
def board_views(tmp_path_factory: pytest.TempPathFactory) -> list[np.ndarray]:
    """20 rendered views of the 9x6 board through :data:`TRUTH`."""
    return render_board_views(tmp_path_factory.mktemp("rendered"), TRUTH, 20)


@pytest.fixture(scope="module")
def video(board_views: list[np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The views, each held for three frames, between frames of the lens without a board."""
    return board_video(tmp_path_factory.mktemp("video") / "boards.avi", board_views)


def capture(video: Path, views: Path, output: Path, *extra: str) -> int:
    return main(["calibrate", "--capture", str(video), "--views", str(views), "--pattern",
                 "9x6", "--square", "0.025", "-o", str(output), *extra])


@pytest.mark.slow
def test_keeps_views_that_add_coverage_then_calibrates(video: Path, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    views, output = tmp_path / "views", tmp_path / "camera.json"
    assert capture(video, views, output, "--min-views", "8", "--coverage", "0.95") == 0
    out = capsys.readouterr().out
    kept = sorted(views.glob("view_*.png"))
    assert 8 <= len(kept) < 20  # a held board is kept once; some views add too little
    assert f"kept {len(kept)} views" in out and "view_000.png: frame 4," in out
    assert f"calibrated on {len(kept)} of {len(kept)} images" in out
    camera = read_camera(output)
    u, v = np.meshgrid(np.arange(100.0, 700.0, 10.0), np.arange(100.0, 500.0, 10.0))
    pixels = np.stack([u.ravel(), v.ravel()], axis=1)
    bearings, valid = TRUTH.lift(pixels)
    recovered, ok = camera.project(bearings[valid])
    assert ok.all() and np.linalg.norm(recovered - pixels[valid], axis=1).max() < 2.0


def test_coverage_counts_only_the_lens_image(board_views: list[np.ndarray]) -> None:
    picker = ViewPicker(BOARD, CaptureGoal(target=0.5, min_views=3, max_views=5))
    dark = np.zeros((600, 800), np.uint8)
    assert picker.look(dark).coverage == 0.0 and picker.kept == 0
    first = picker.look(board_views[0])
    assert first.kept and first.new_cells >= 3 and 0 < first.coverage < 0.5
    again = picker.look(board_views[0])  # the same view adds nothing
    assert not again.kept and again.new_cells == 0 and again.coverage == first.coverage
    image_cells = (cv2.resize(board_views[0], GRID, interpolation=cv2.INTER_AREA) > 12).sum()
    assert image_cells < GRID[0] * GRID[1]  # the black corners outside the circle do not count


def test_a_video_without_boards_is_one_line(board_views: list[np.ndarray], tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "empty.avi"
    write_video(path, [np.where(board_views[0] > 0, 128, 0).astype(np.uint8)] * 5)
    assert capture(path, tmp_path / "views", tmp_path / "camera.json") == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "kept 0 views, need 12: show the whole board" in err
    assert not (tmp_path / "camera.json").exists()


@pytest.mark.parametrize(("extra", "message"), [
    (["--coverage", "0"], "argument --coverage: must be a finite number > 0 and <= 1"),
    (["--min-views", "2"], "at least 3 views are needed, got 2"),
    (["--min-views", "20", "--max-views", "10"], "max views 10 < min views 20"),
])
def test_bad_goals_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                               extra: list[str], message: str) -> None:
    try:
        code = capture(tmp_path / "none.avi", tmp_path / "views", tmp_path / "c.json", *extra)
    except SystemExit as exited:  # argparse's usage error
        code = exited.code
    assert code in (1, 2) and message in capsys.readouterr().err


def test_a_views_folder_holding_files_is_refused(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    views = tmp_path / "views"
    views.mkdir()
    (views / "mine.txt").write_text("keep")
    assert capture(tmp_path / "none.avi", views, tmp_path / "c.json") == 1
    assert "exists and is not an empty folder" in capsys.readouterr().err
    assert (views / "mine.txt").read_text() == "keep"
