"""Tests of ``vmnav vision pair`` (tools/vision_pair_cmd.py, tools/figures/pair_matches.py)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.config import FeatureConfig
from robot.vision.epipolar import rotation_from_rotvec
from robot.vision.two_view import direction_error_deg, relative_pose_from_body, rotation_error_deg
from shared.kannala_brandt_yaml import read_equidistant_yaml
from tools.bench.realdata import (
    DIRECTION_TOLERANCE_DEG,
    FISHEYE_LEFT_IMAGE,
    FISHEYE_LEFT_YAML,
    FISHEYE_RIGHT_IMAGE,
    FISHEYE_RIGHT_YAML,
    ROTATION_TOLERANCE_DEG,
)
from tools.cli import main


@pytest.fixture(scope="module")
def calibrations(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The pair's two calibrations imported with ``vmnav calibrate --from-equidistant``."""
    folder = tmp_path_factory.mktemp("cams")
    paths = folder / "left.json", folder / "right.json"
    for yaml, path in zip((FISHEYE_LEFT_YAML, FISHEYE_RIGHT_YAML), paths, strict=True):
        assert main(["calibrate", "--from-equidistant", str(yaml), "--out", str(path)]) == 0
    return paths


def test_the_real_pair(calibrations: tuple[Path, Path], tmp_path: Path,
                       capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    picture = tmp_path / "pair.png"
    # Harris + ZNCC with corners over the whole image, through --config.
    config = tmp_path / "vmnav.toml"
    config.write_text('[features]\nmethod = "harris-zncc"\nmax_corners = 1000\n'
                      "quality_level = 0.001\n")
    code = main(["vision", "pair", str(FISHEYE_LEFT_IMAGE), str(FISHEYE_RIGHT_IMAGE),
                 "--calibration", str(calibrations[0]), "--calibration-b", str(calibrations[1]),
                 "--config", str(config), "--out", str(picture)])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert report["method"] == "harris-zncc"
    assert report["corners_a"] > 100 and report["corners_b"] > 100
    assert report["corners_a"] >= report["matches"] >= report["inliers"] > 100
    assert report["ok"] is True and report["convention"] == "X_b = R X_a + t"
    assert report["time_ms"] > 0
    assert report["parallax_deg"] > 0.5  # 0.12 m of baseline, points a few metres away
    rotvec = np.radians(report["rotation_vector_deg"])
    assert report["rotation_deg"] == pytest.approx(np.degrees(np.linalg.norm(rotvec)), abs=1e-3)
    direction = np.array(report["translation_direction"])
    assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-4)
    R_ref, t_ref = relative_pose_from_body(read_equidistant_yaml(FISHEYE_LEFT_YAML).T_body_sensor,
                                           read_equidistant_yaml(FISHEYE_RIGHT_YAML).T_body_sensor)
    assert rotation_error_deg(rotation_from_rotvec(rotvec), R_ref) < ROTATION_TOLERANCE_DEG
    assert direction_error_deg(direction, t_ref) < DIRECTION_TOLERANCE_DEG
    drawn = cv2.imread(str(picture))
    assert drawn.shape == (480 + 28, 2 * 752, 3)
    # Inliers are drawn in green.
    green = (drawn[:, :, 1] > 150) & (drawn[:, :, 0] < 120) & (drawn[:, :, 2] < 120)
    assert green.sum() > 1000


def test_one_calibration_for_both(calibrations: tuple[Path, Path], tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    picture = tmp_path / "same.jpg"
    assert main(["vision", "pair", str(FISHEYE_LEFT_IMAGE), str(FISHEYE_LEFT_IMAGE),
                 "--calibration", str(calibrations[0]), "--out", str(picture)]) == 0
    assert picture.read_bytes()[:2] == b"\xff\xd8"  # a JPEG, by the name
    report = json.loads(capsys.readouterr().out)
    # The same image twice, the default front end: nearly every point matches itself, the
    # matches are exact, and there is no translation.
    assert report["method"] == FeatureConfig().method
    assert report["matches"] >= 0.9 * report["corners_a"] and report["rotation_deg"] < 0.01
    assert report["parallax_deg"] < 0.01


def fails(capsys: pytest.CaptureFixture[str], code: int, *fragments: str) -> None:
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("vmnav vision: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, err


def test_bad_input(calibrations: tuple[Path, Path], tmp_path: Path,
                   capsys: pytest.CaptureFixture[str]) -> None:
    left, _ = calibrations
    code = main(["vision", "pair", str(tmp_path / "no.png"), str(FISHEYE_RIGHT_IMAGE),
                 "--calibration", str(left)])
    fails(capsys, code, f"{tmp_path / 'no.png'}: cannot read the image")
    small = tmp_path / "small.png"
    cv2.imwrite(str(small), np.zeros((48, 64), np.uint8))
    code = main(["vision", "pair", str(FISHEYE_LEFT_IMAGE), str(small), "--calibration", str(left)])
    fails(capsys, code, f"{left}: calibration is for 752x480 but images are 64x48")
    code = main(["vision", "pair", str(FISHEYE_LEFT_IMAGE), str(FISHEYE_RIGHT_IMAGE),
                 "--calibration", str(FISHEYE_LEFT_YAML)])
    fails(capsys, code, f"{FISHEYE_LEFT_YAML}: ")
    bad_config = tmp_path / "bad.toml"
    bad_config.write_text('[features]\nmethod = "magic"\n')
    code = main(["vision", "pair", str(FISHEYE_LEFT_IMAGE), str(FISHEYE_RIGHT_IMAGE),
                 "--calibration", str(left), "--config", str(bad_config)])
    fails(capsys, code, f"{bad_config}", "method must be one of")
    text = tmp_path / "notes.png"
    text.write_text("not an image")
    code = main(["vision", "pair", str(text), str(FISHEYE_RIGHT_IMAGE), "--calibration", str(left)])
    fails(capsys, code, f"{text}: not an image of a format read here")
