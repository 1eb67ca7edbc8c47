"""Tests of shared/kannala_brandt_yaml.py: reading an equidistant calibration file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shared.errors import CalibrationError
from shared.kannala_brandt_yaml import read_equidistant_yaml
from tools.bench.realdata import FISHEYE_LEFT_YAML, FISHEYE_RIGHT_YAML

GOOD = """%YAML:1.0
camera_id: test
T_BS:
  cols: 4
  rows: 4
  data: [1, 0, 0, 0.1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
resolution: [640, 480]
camera_model: pinhole
intrinsics: [300.0, 301.0, 320.5, 240.5]
distortion_model: equidistant
distortion_coefficients: [0.01, -0.002, 0.0003, 0.0]
"""


def test_reads_the_vendored_pair() -> None:
    left = read_equidistant_yaml(FISHEYE_LEFT_YAML)
    right = read_equidistant_yaml(FISHEYE_RIGHT_YAML)
    assert (left.camera.width, left.camera.height) == (752, 480)
    assert (left.camera.fx, left.camera.fy, left.camera.cx, left.camera.cy) == (
        366.163, 365.631, 380.573, 225.950)
    assert np.allclose(left.camera.k, [-0.020476443, -0.007108226, 0.002180580, -0.001192386])
    assert right.T_body_sensor is not None and right.T_body_sensor[1, 3] == 0.122004189


def test_reads_a_file_written_like_kalibr(tmp_path: Path) -> None:
    path = tmp_path / "cam.yaml"
    path.write_text(GOOD)
    calibration = read_equidistant_yaml(path)
    assert calibration.camera.fy == 301.0 and calibration.camera.k[2] == 0.0003
    assert calibration.T_body_sensor is not None
    assert calibration.T_body_sensor[0, 3] == 0.1
    path.write_text(GOOD.split("T_BS:")[0] + GOOD.split("  data: [1, 0, 0, 0.1, 0, 1, 0, 0, 0, "
                                                    "0, 1, 0, 0, 0, 0, 1]\n")[1])
    assert read_equidistant_yaml(path).T_body_sensor is None


@pytest.mark.parametrize(("text", "problem"), [
    ("", "empty file"),
    ("just text", "not OpenCV YAML: line 1:"),
    ("%YAML:1.0\nintrinsics: [1, 2\n", "not OpenCV YAML: line 2:"),
    (GOOD.replace("resolution: [640, 480]\n", ""), "missing key 'resolution'"),
    (GOOD.replace("[640, 480]", "[640.5, 480]"), "resolution: expected two positive integers"),
    (GOOD.replace("[300.0, 301.0, 320.5, 240.5]", "[300.0, 301.0, 320.5]"),
     "intrinsics: expected a list of 4 numbers"),
    (GOOD.replace("[300.0, 301.0,", "[300.0, fast,"), "intrinsics[1]: expected a finite number"),
    (GOOD.replace("[300.0, 301.0,", "[-300.0, 301.0,"), "intrinsics: fu and fv must be > 0"),
    (GOOD.replace("distortion_model: equidistant", "distortion_model: radtan"),
     "distortion_model: expected 'equidistant', got 'radtan'"),
    (GOOD.replace("camera_model: pinhole", "camera_model: omni"),
     "camera_model: expected 'pinhole', got 'omni'"),
    (GOOD.replace("rows: 4", "rows: 3"), "T_BS: expected 4 rows and 4 cols"),
    (GOOD.replace("[1, 0, 0, 0.1,", "[2, 0, 0, 0.1,"), "T_BS: not a rigid transform"),
])
def test_bad_files(tmp_path: Path, text: str, problem: str) -> None:
    path = tmp_path / "cam.yaml"
    path.write_text(text)
    with pytest.raises(CalibrationError) as info:
        read_equidistant_yaml(path)
    assert str(info.value).startswith(f"{path}: ") and problem in str(info.value)
    assert "\n" not in str(info.value)


def test_missing_and_binary_files(tmp_path: Path) -> None:
    with pytest.raises(CalibrationError, match=r"nope\.yaml: file not found"):
        read_equidistant_yaml(tmp_path / "nope.yaml")
    (tmp_path / "b.yaml").write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(CalibrationError, match=r"b\.yaml: not UTF-8 text"):
        read_equidistant_yaml(tmp_path / "b.yaml")
