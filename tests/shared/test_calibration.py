"""Tests of shared/calibration.py: the camera calibration JSON file."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from shared.calibration import (
    camera_from_dict,
    camera_to_dict,
    check_image_size,
    check_replaceable,
    read_camera,
    write_camera,
)
from shared.camera_model import CameraModel
from shared.chessboard import Chessboard
from shared.errors import CalibrationError, InputError
from sim.checkerboard import sample_board_poses

DISTORTED = CameraModel(
    width=640,
    height=480,
    K=np.array([[301.25, 0.125, 320.5], [0.0, 300.75, 240.25], [0.0, 0.0, 1.0]]),
    xi=1.05,
    D=np.array([-0.2, 0.03, 1e-4, -2e-4]),
    fov_deg=190.0,
)


def assert_same_camera(a: CameraModel, b: CameraModel) -> None:
    assert (a.width, a.height, a.xi, a.fov_deg) == (b.width, b.height, b.xi, b.fov_deg)
    np.testing.assert_array_equal(a.K, b.K)
    np.testing.assert_array_equal(a.D, b.D)


def valid_data() -> dict[str, Any]:
    return camera_to_dict(CameraModel.default(), rms_px=0.2, source="test")


class TestWriteRead:
    @pytest.mark.parametrize("camera", [CameraModel.default(), DISTORTED])
    def test_round_trip(self, tmp_path: Path, camera: CameraModel) -> None:
        path = tmp_path / "camera.json"
        write_camera(path, camera, rms_px=0.31, source="unit test")
        assert_same_camera(read_camera(path), camera)

    def test_file_content_is_the_documented_format(self, tmp_path: Path) -> None:
        path = tmp_path / "camera.json"
        write_camera(path, DISTORTED, rms_px=0.31, source="unit test")
        data = json.loads(path.read_text())
        assert data == {
            "format": "vmnav-camera",
            "format_version": 1,
            "model": "omnidir-mei",
            "image_size": [640, 480],
            "K": [[301.25, 0.125, 320.5], [0.0, 300.75, 240.25], [0.0, 0.0, 1.0]],
            "xi": 1.05,
            "D": [-0.2, 0.03, 1e-4, -2e-4],
            "fov_deg": 190.0,
            "rms_px": 0.31,
            "source": "unit test",
        }
        # One field per line: K reads as a matrix.
        assert (
            '"K": [[301.25, 0.125, 320.5], [0.0, 300.75, 240.25], [0.0, 0.0, 1.0]]'
            in path.read_text()
        )

    def test_optional_fields_are_null(self, tmp_path: Path) -> None:
        path = tmp_path / "camera.json"
        write_camera(path, CameraModel.default())
        data = json.loads(path.read_text())
        assert data["rms_px"] is None and data["source"] is None

    def test_round_trip_of_what_omnidir_calibrate_returns(
        self, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        # Exact corners of 8 views through a known camera -> cv2.omnidir.calibrate.
        truth = CameraModel(
            800, 600, CameraModel.default().K, 1.2, np.array([-0.1, 0.02, 1e-3, -1e-3])
        )
        board = Chessboard(9, 6, 0.025)
        poses = sample_board_poses(truth, board, rng, 8)
        object_points = board.object_points()
        image_points = [truth.project(object_points @ p.R_c_b.T + p.t_c_b)[0] for p in poses]
        _, K, xi, D, _, _, _ = cv2.omnidir.calibrate(
            [object_points.reshape(-1, 1, 3)] * len(poses),
            [p.reshape(-1, 1, 2) for p in image_points],
            (800, 600),
            None,
            None,
            None,
            0,
            (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-10),
        )
        assert (K.shape, K.dtype, xi.shape, D.shape) == ((3, 3), np.float64, (1, 1), (1, 4))
        path = tmp_path / "camera.json"
        write_camera(path, CameraModel(800, 600, K, xi, D, 185.0))
        back = read_camera(path)
        np.testing.assert_array_equal(back.K, K)
        assert back.xi == xi[0, 0]
        np.testing.assert_array_equal(back.D, D.ravel())

    def test_dict_round_trip_for_embedding(self) -> None:
        assert_same_camera(
            camera_from_dict(camera_to_dict(DISTORTED), "memory.json: camera"), DISTORTED
        )


class TestAtomicWrite:
    def test_invalid_camera_leaves_the_old_file(self, tmp_path: Path) -> None:
        path = tmp_path / "camera.json"
        write_camera(path, CameraModel.default(), source="old")
        before = path.read_bytes()
        K = CameraModel.default().K.copy()
        K[0, 2] = math.nan
        with pytest.raises(CalibrationError, match=r"camera\.json: refusing to write .*K\[0\]"):
            write_camera(path, CameraModel(800, 600, K, 1.6))
        assert path.read_bytes() == before
        assert os.listdir(tmp_path) == ["camera.json"]

    def test_failed_rename_leaves_the_old_file(
        self, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
    ) -> None:
        path = tmp_path / "camera.json"
        write_camera(path, CameraModel.default(), source="old")
        before = path.read_bytes()

        def fail(src: str, dst: str) -> None:
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(os, "replace", fail)
        with pytest.raises(InputError, match=r"camera\.json: cannot write"):
            write_camera(path, DISTORTED)
        assert path.read_bytes() == before
        assert os.listdir(tmp_path) == ["camera.json"]

    def test_missing_folder(self, tmp_path: Path) -> None:
        with pytest.raises(InputError, match="cannot write"):
            write_camera(tmp_path / "nowhere" / "camera.json", CameraModel.default())


def _set(key: str, value: Any) -> dict[str, Any]:
    data = valid_data()
    data[key] = value
    return data


def _without(key: str) -> dict[str, Any]:
    data = valid_data()
    del data[key]
    return data


def _with_k(row: int, col: int, value: Any) -> dict[str, Any]:
    data = valid_data()
    data["K"][row][col] = value
    return data


BAD_FILES: dict[str, tuple[str, str]] = {
    # name: (file text, expected message fragment)
    "not json": ("{", "not valid JSON (truncated?): Expecting property name"),
    "empty": ("", "not valid JSON"),
    "nan constant": (
        json.dumps(valid_data()).replace('"xi": 1.6', '"xi": NaN'),
        "NaN is not a JSON number",
    ),
    "overflow to inf": (
        json.dumps(valid_data()).replace('"xi": 1.6', '"xi": 1e999'),
        "not valid JSON: number 1e999 is too large for a float",
    ),
    "array": ("[1, 2]", "expected a JSON object, got an array"),
    "missing xi": (json.dumps(_without("xi")), "missing field 'xi'"),
    "missing rms": (json.dumps(_without("rms_px")), "missing field 'rms_px'"),
    "unknown field": (json.dumps(_set("focal", 3)), "unknown field 'focal'"),
    "format": (json.dumps(_set("format", "opencv")), "format: expected 'vmnav-camera'"),
    "version 2": (json.dumps(_set("format_version", 2)), "format_version 2 is not supported"),
    "version string": (
        json.dumps(_set("format_version", "1")),
        "format_version: expected an integer",
    ),
    "version bool": (
        json.dumps(_set("format_version", True)),
        "format_version: expected an integer",
    ),
    "model": (json.dumps(_set("model", "kannala-brandt")), "model: expected 'omnidir-mei'"),
    "size one int": (json.dumps(_set("image_size", [800])), "image_size: expected [width, height]"),
    "size zero": (json.dumps(_set("image_size", [800, 0])), "image_size"),
    "size float": (json.dumps(_set("image_size", [800.0, 600])), "image_size"),
    "size string": (json.dumps(_set("image_size", "800x600")), "image_size"),
    "size bool": (json.dumps(_set("image_size", [True, 600])), "image_size"),
    "K not a list": (json.dumps(_set("K", 3)), "K: expected 3 rows of 3 numbers, got an integer 3"),
    "K 2 rows": (json.dumps(_set("K", [[1, 0, 0], [0, 1, 0]])), "K: expected 3 rows"),
    "K short row": (
        json.dumps(_set("K", [[1, 0], [0, 1, 0], [0, 0, 1]])),
        "K[0]: expected 3 numbers",
    ),
    "K string": (json.dumps(_with_k(0, 2, "400")), "K[0]: expected a number, got a string"),
    "K bool": (json.dumps(_with_k(1, 2, False)), "K[1]: expected a number, got a boolean"),
    "K null": (json.dumps(_with_k(1, 1, None)), "K[1]: expected a number, got null"),
    "fx zero": (json.dumps(_with_k(0, 0, 0.0)), "K: fx and fy must be > 0"),
    "fy negative": (json.dumps(_with_k(1, 1, -300.0)), "K: fx and fy must be > 0"),
    "cx outside": (json.dumps(_with_k(0, 2, 5000.0)),
                   "K: the principal point (5000, 299.5) px is outside the 800x600 image"),
    "cy negative": (json.dumps(_with_k(1, 2, -1.0)),
                    "K: the principal point (399.5, -1) px is outside the 800x600 image"),
    "K10": (json.dumps(_with_k(1, 0, 0.5)), "K: rows 2 and 3 must be [0, fy, cy] and [0, 0, 1]"),
    "K22": (json.dumps(_with_k(2, 2, 2.0)), "K: rows 2 and 3 must be [0, fy, cy] and [0, 0, 1]"),
    "K20": (json.dumps(_with_k(2, 0, 1e-9)), "K: rows 2 and 3 must be [0, fy, cy] and [0, 0, 1]"),
    "xi negative": (json.dumps(_set("xi", -0.1)), "xi: must be >= 0, got -0.1"),
    "xi string": (json.dumps(_set("xi", "1.6")), "xi: expected a number, got a string"),
    "xi list": (json.dumps(_set("xi", [1.6])), "xi: expected a number, got an array"),
    "D length": (json.dumps(_set("D", [0, 0, 0, 0, 0])), "D: expected 4 numbers"),
    "D null": (json.dumps(_set("D", [0, None, 0, 0])), "D: expected a number, got null"),
    "fov zero": (json.dumps(_set("fov_deg", 0)), "fov_deg: must be in (0, 360) degrees"),
    "fov 360": (json.dumps(_set("fov_deg", 360)), "fov_deg: must be in (0, 360) degrees"),
    "fov negative": (json.dumps(_set("fov_deg", -185)), "fov_deg: must be in (0, 360) degrees"),
    "rms negative": (json.dumps(_set("rms_px", -1)), "rms_px: must be >= 0 or null"),
    "rms string": (json.dumps(_set("rms_px", "small")), "rms_px: expected a number"),
    "source number": (json.dumps(_set("source", 7)), "source: expected a string or null"),
}


class TestReadErrors:
    @pytest.mark.parametrize("case", sorted(BAD_FILES))
    def test_bad_file(self, tmp_path: Path, case: str) -> None:
        text, fragment = BAD_FILES[case]
        path = tmp_path / "camera.json"
        path.write_text(text)
        with pytest.raises(CalibrationError) as info:
            read_camera(path)
        message = str(info.value)
        assert message.startswith(f"{path}: ")
        assert fragment in message
        assert "\n" not in message
        assert info.value.where == str(path)

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(CalibrationError, match=r"nope\.json: file not found"):
            read_camera(tmp_path / "nope.json")

    def test_folder_instead_of_file(self, tmp_path: Path) -> None:
        with pytest.raises(CalibrationError, match="cannot read"):
            read_camera(tmp_path)

    def test_not_utf8(self, tmp_path: Path) -> None:
        path = tmp_path / "camera.json"
        path.write_bytes(b"\xff\xfe\x00")
        with pytest.raises(CalibrationError, match=r"camera\.json: cannot read"):
            read_camera(path)

    def test_valid_file_reads(self, tmp_path: Path) -> None:
        path = tmp_path / "camera.json"
        path.write_text(json.dumps(valid_data()))
        assert_same_camera(read_camera(path), CameraModel.default())


class TestCheckImageSize:
    def test_matching_size_passes(self) -> None:
        check_image_size(CameraModel.default(), 800, 600, "camera.json")

    @pytest.mark.parametrize(("width", "height"), [(640, 480), (600, 800), (800, 601)])
    def test_mismatch(self, width: int, height: int) -> None:
        with pytest.raises(CalibrationError) as info:
            check_image_size(CameraModel.default(), width, height, "camera.json")
        assert (
            str(info.value)
            == f"camera.json: calibration is for 800x600 but images are {width}x{height}"
        )


class TestCheckReplaceable:
    def test_absent_or_own_files_may_be_replaced(self, tmp_path: Path) -> None:
        check_replaceable(tmp_path / "new.json", "vmnav calibrate")
        write_camera(tmp_path / "c.json", CameraModel.default(), source="vmnav calibrate: x")
        check_replaceable(tmp_path / "c.json", "vmnav calibrate")

    @pytest.mark.parametrize("content", [
        None,  # a calibration written by someone else
        "not json",
        "[1, 2]",
        '{"format": "other", "source": "vmnav calibrate"}',
    ])
    def test_other_files_are_refused(self, tmp_path: Path, content: str | None) -> None:
        path = tmp_path / "c.json"
        if content is None:
            write_camera(path, CameraModel.default(), source="by hand")
        else:
            path.write_text(content)
        before = path.read_bytes()
        with pytest.raises(CalibrationError, match=f"{path}: exists and was not written by "
                                                   "vmnav calibrate: not replacing it"):
            check_replaceable(path, "vmnav calibrate")
        assert path.read_bytes() == before

    def test_a_folder_is_refused(self, tmp_path: Path) -> None:
        with pytest.raises(CalibrationError, match="exists and was not written"):
            check_replaceable(tmp_path, "vmnav calibrate")
