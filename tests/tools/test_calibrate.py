"""Tests of ``vmnav calibrate`` (tools/calibrate.py) through the command line."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.calibration import read_camera, write_camera
from shared.camera_model import CameraModel
from sim.checkerboard import write_synthetic_set
from tools.bench.realdata import (
    CATADIOPTRIC_DIR,
    CATADIOPTRIC_MISSING,
    CATADIOPTRIC_REFERENCE,
    FISHEYE_LEFT_YAML,
    FOCAL_TOLERANCE,
    XI_TOLERANCE,
)
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
        assert_fails(code, capsys, f"{tmp_path}: no images (.png, .jpg, .jpeg, .jpe, .pgm")

    @pytest.mark.slow
    def test_corrupt_image(
        self, views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        shutil.copy(views / "view_000.png", tmp_path / "a.png")
        (tmp_path / "b.jpg").write_bytes(b"\xff\xd8 not really a jpeg")
        code = calibrate(tmp_path, tmp_path / "c.json")
        assert_fails(code, capsys, f"{tmp_path / 'b.jpg'}: corrupt JPEG")

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
        write_camera(output, CameraModel.default(), source="vmnav calibrate: an earlier run")
        before = output.read_bytes()
        (tmp_path / "empty").mkdir()
        assert calibrate(tmp_path / "empty", output) == 1
        assert output.read_bytes() == before


@pytest.mark.slow
def test_reads_pgm_bmp_tiff_and_warns_of_a_duplicate_view(
    views: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for k, path in enumerate(sorted(views.glob("*.png"))[:6]):
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        cv2.imwrite(str(tmp_path / f"v{k}.{('bmp', 'pgm', 'tif')[k % 3]}"), image)
    shutil.copy(tmp_path / "v1.pgm", tmp_path / "v10.pgm")
    assert calibrate(tmp_path, tmp_path / "c.json") == 0
    out = capsys.readouterr().out
    assert "7 images in" in out and "board found in 7" in out
    # Numbers in names sort by value: v10 after v5.
    assert out.index("v5.tif: used") < out.index("v10.pgm: used")
    assert ("warning: v10.pgm: nearly the same board pose as v1.pgm (corners 0.0 px apart, "
            "RMS): a duplicate view") in out
    assert "outlier" not in out


@pytest.mark.slow
@pytest.mark.skipif(not CATADIOPTRIC_DIR.is_dir(), reason=CATADIOPTRIC_MISSING)
def test_reproduces_opencvs_catadioptric_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    output = tmp_path / "cata.json"
    assert calibrate(CATADIOPTRIC_DIR, output) == 0
    out = capsys.readouterr().out
    assert "18 images in" in out and "board found in 17" in out
    assert "warning: 12.jpg: rms 1.7" in out and "an outlier view" in out
    assert "duplicate" not in out
    camera = read_camera(output)
    ref = CATADIOPTRIC_REFERENCE
    assert camera.K[0, 0] == pytest.approx(ref["fx"], rel=FOCAL_TOLERANCE)
    assert camera.K[1, 1] == pytest.approx(ref["fy"], rel=FOCAL_TOLERANCE)
    assert camera.xi == pytest.approx(ref["xi"], abs=XI_TOLERANCE)


class TestFromEquidistant:
    def test_imports_the_fisheye_pair_calibration(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        output = tmp_path / "left.json"
        assert main(["calibrate", "--from-equidistant", str(FISHEYE_LEFT_YAML),
                     "--out", str(output)]) == 0
        out = capsys.readouterr().out
        assert "equidistant camera 752x480, fx 366.163 fy 365.631" in out
        assert "unified model fitted (xi, no distortion) on 640 pixels: residual RMS 0.045 px, " \
               "max 0.151 px" in out
        camera = read_camera(output)
        assert (camera.width, camera.height, camera.fov_deg) == (752, 480, 152.0)
        assert camera.xi == pytest.approx(2.3746, abs=1e-3)
        assert "residual RMS 0.045 px" in output.read_text()
        # Its own file may be replaced by a second run.
        assert main(["calibrate", "--from-equidistant", str(FISHEYE_LEFT_YAML),
                     "--out", str(output)]) == 0

    def test_refuses_to_replace_another_file(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        output = tmp_path / "left.yaml"
        shutil.copy(FISHEYE_LEFT_YAML, output)
        code = main(["calibrate", "--from-equidistant", str(output), "--out", str(output)])
        assert_fails(code, capsys, f"{output}: exists and was not written by vmnav calibrate")
        assert output.read_bytes() == FISHEYE_LEFT_YAML.read_bytes()

    def test_bad_yaml(self, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
        bad = tmp_path / "bad.yaml"
        bad.write_text("%YAML:1.0\nintrinsics: [1, 2\n")
        code = main(["calibrate", "--from-equidistant", str(bad), "--out", str(tmp_path / "c")])
        assert_fails(code, capsys, f"{bad}: not OpenCV YAML: line 2:")
        assert not (tmp_path / "c").exists()

    def test_images_or_yaml_not_both(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code = main(["calibrate", str(tmp_path), "--from-equidistant", str(FISHEYE_LEFT_YAML),
                     "--out", str(tmp_path / "c.json")])
        assert_fails(code, capsys, "give a folder of board images, --capture SOURCE or "
                                   "--from-equidistant YAML")
        code = main(["calibrate", str(tmp_path), "--out", str(tmp_path / "c.json")])
        assert_fails(code, capsys, "--pattern/--square: both are needed")
        code = main(["calibrate", "--from-equidistant", str(FISHEYE_LEFT_YAML), "--fov", "190",
                     "--out", str(tmp_path / "c.json")])
        assert_fails(code, capsys, "--fov: not used with --from-equidistant")
