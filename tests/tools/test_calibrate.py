"""Tests of ``vmnav calibrate`` (tools/calibrate.py) through the command line."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.calibration import read_camera
from shared.camera_model import CameraModel
from sim.checkerboard import write_synthetic_set
from tools.cli import main

#: The camera behind the synthetic images: the default lens with real distortion.
TRUTH = CameraModel(
    800, 600, CameraModel.default().K, 1.6, np.array([-0.05, 0.01, 0.001, -0.0005]), 185.0
)
N_VIEWS = 12


@pytest.fixture(scope="module")
def views(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """12 rendered 9x6 board views (25 mm squares) through :data:`TRUTH`, as PNG."""
    folder = tmp_path_factory.mktemp("views")
    write_synthetic_set(folder, TRUTH, np.random.default_rng(7), N_VIEWS)
    return folder


def calibrate(images: Path | str, output: Path, *extra: str) -> int:
    args = ["calibrate", str(images), "--pattern", "9x6", "--square", "0.025", "-o", str(output)]
    return main([*args, *extra])


@pytest.mark.slow
def test_recovers_the_camera(
    views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "camera.json"
    assert calibrate(views, output) == 0
    out = capsys.readouterr().out
    assert f"{N_VIEWS} images in {views}" in out
    assert "view_000.png: used, rms" in out
    assert f"wrote {output}" in out

    camera = read_camera(output)
    assert (camera.width, camera.height, camera.fov_deg) == (800, 600, 185.0)
    rms_px = float(out.split("RMS reprojection error ")[1].split(" px")[0])
    assert rms_px < 0.5
    # Compare by reprojection (xi, f and k1 trade off): every valid pixel of the
    # true camera, lifted to its true bearing, must land within 1 px.
    u, v = np.meshgrid(np.arange(0.0, 800.0, 2.0), np.arange(0.0, 600.0, 2.0))
    pixels = np.stack([u.ravel(), v.ravel()], axis=1)
    bearings, valid = TRUTH.lift(pixels)
    recovered, ok = camera.project(bearings[valid])
    assert ok.all()
    err = np.linalg.norm(recovered - pixels[valid], axis=1)
    assert err.max() < 1.0
    beyond_90 = bearings[valid][:, 2] < 0.0
    assert beyond_90.sum() > 1000 and err[beyond_90].max() < 1.0


@pytest.mark.slow
def test_writes_the_result_of_the_run(views: Path, tmp_path: Path) -> None:
    # Output to another name, with another FOV; the file says where it came from.
    output = tmp_path / "other.json"
    assert calibrate(views, output, "--fov", "190") == 0
    assert read_camera(output).fov_deg == 190.0
    assert f"images in {views}" in output.read_text()


def assert_fails(code: int, capsys: pytest.CaptureFixture[str], *fragments: str) -> None:
    """Exit code 1 and one line on stderr that contains every fragment."""
    err = capsys.readouterr().err
    assert code == 1
    assert err.startswith("vmnav calibrate: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, err


class TestBadInput:
    def test_missing_folder(self, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
        code = calibrate(tmp_path / "nope", tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'nope'}: folder not found")

    def test_file_instead_of_folder(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        (tmp_path / "a.png").write_bytes(b"")
        code = calibrate(tmp_path / "a.png", tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'a.png'}: not a folder")

    def test_no_images(self, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
        (tmp_path / "notes.txt").write_text("no images here")
        code = calibrate(tmp_path, tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path}: no images (.png, .jpg, .jpeg, .bmp)")

    @pytest.mark.slow
    def test_corrupt_image(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        shutil.copy(views / "view_000.png", tmp_path / "a.png")
        (tmp_path / "b.jpg").write_bytes(b"\xff\xd8 not really a jpeg")
        code = calibrate(tmp_path, tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'b.jpg'}: cannot read the image")

    @pytest.mark.slow
    def test_images_of_different_sizes(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        shutil.copy(views / "view_000.png", tmp_path / "a.png")
        cv2.imwrite(str(tmp_path / "b.png"), np.zeros((480, 640), np.uint8))
        code = calibrate(tmp_path, tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'b.png'}: image is 640x480 but a.png is 800x600")

    @pytest.mark.parametrize(
        ("option", "value", "fragment"),
        [
            (
                "--pattern",
                "9by6",
                "--pattern: expected inner corners as COLSxROWS like 9x6, got '9by6'",
            ),
            ("--pattern", "1x6", "--pattern: need at least 2x2 inner corners"),
            ("--square", "big", "--square: expected a number, got 'big'"),
            ("--square", "-0.025", "--square: must be > 0 m"),
            ("--square", "nan", "--square: expected a finite number"),
            ("--fov", "0", "--fov: must be in (0, 360) degrees"),
            ("--fov", "400", "--fov: must be in (0, 360) degrees"),
        ],
    )
    @pytest.mark.slow
    def test_bad_option(
        self,
        views: Path,
        tmp_path: Path,
        capsys: pytest.CaptureFixture[str],
        option: str,
        value: str,
        fragment: str,
    ) -> None:
        args = {"--pattern": "9x6", "--square": "0.025", "--fov": "185", option: value}
        code = main(
            [
                "calibrate",
                str(views),
                "-o",
                str(tmp_path / "c.json"),
                *[x for kv in args.items() for x in kv],
            ]
        )
        assert_fails(code, capsys, fragment)
        assert not (tmp_path / "c.json").exists()

    @pytest.mark.slow
    def test_too_few_boards(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        for name in ("view_000.png", "view_001.png"):
            shutil.copy(views / name, tmp_path / name)
        cv2.imwrite(str(tmp_path / "view_002.png"), np.full((600, 800), 128, np.uint8))
        code = calibrate(tmp_path, tmp_path / "c.json")
        assert_fails(
            code, capsys, f"{tmp_path}: the board was found in 2 image(s); need at least 3"
        )

    @pytest.mark.slow
    def test_wrong_pattern_finds_no_board(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code = main(
            [
                "calibrate",
                str(views),
                "--pattern",
                "10x7",
                "--square",
                "0.025",
                "-o",
                str(tmp_path / "c.json"),
            ]
        )
        assert_fails(code, capsys, f"{views}: the board was found in 0 image(s)")

    @pytest.mark.slow
    def test_unwritable_output(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code = calibrate(views, tmp_path / "missing" / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'missing' / 'c.json'}: cannot write")

    def test_existing_output_survives_a_failed_run(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        output = tmp_path / "camera.json"
        output.write_text("precious")
        (tmp_path / "empty").mkdir()
        assert calibrate(tmp_path / "empty", output) == 1
        assert output.read_text() == "precious"
