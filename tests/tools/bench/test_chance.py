"""Unrelated real images through localization's acceptance test (tools/bench/chance.py)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.config import VmnavConfig
from shared.camera_model import CameraModel
from shared.errors import InputError
from tools.bench.chance import (
    DEFAULT_REALDATA,
    ChanceImage,
    fitted_to_camera,
    load_images,
    real_sets,
    skimage_paths,
    summary,
    try_pairs,
)
from tools.bench.targets import targets_of
from tools.cli import main

CAMERA = CameraModel.default()
CONFIG = VmnavConfig()
needs_realdata = pytest.mark.skipif(not DEFAULT_REALDATA.is_dir(),
                                    reason="needs ../shared/realdata")


def _skimage(name: str) -> ChanceImage:
    (path,) = [p for p in skimage_paths() if p.name == name]
    grey = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    return ChanceImage(f"skimage/{name}", f"skimage/{path.stem}", fitted_to_camera(grey, CAMERA))


class TestImages:
    @pytest.mark.parametrize("shape", [(480, 752), (960, 1280), (512, 512), (300, 200)])
    def test_fitted_to_the_camera(self, shape: tuple[int, int]) -> None:
        image = np.random.default_rng(0).integers(0, 256, shape, dtype=np.uint8)
        fitted = fitted_to_camera(image, CAMERA)
        assert fitted.shape == (CAMERA.height, CAMERA.width) and fitted.dtype == np.uint8

    def test_a_set_in_two_roots_is_read_once(self, tmp_path: Path) -> None:
        for root in ("a", "b"):
            (tmp_path / root / "place").mkdir(parents=True)
            cv2.imwrite(str(tmp_path / root / "place" / "1.png"), np.zeros((8, 8), np.uint8))
        (tmp_path / "b" / "place" / "notes.txt").write_text("not an image")
        sets = real_sets([tmp_path / "a", tmp_path / "b"])
        assert list(sets) == ["place"]
        assert sets["place"] == [tmp_path / "a" / "place" / "1.png"]

    def test_no_folder_is_one_line(self, tmp_path: Path) -> None:
        with pytest.raises(InputError, match="no such folder of real image sets"):
            real_sets([tmp_path / "missing"])

    def test_a_file_that_does_not_decode_is_named(self, tmp_path: Path) -> None:
        (tmp_path / "place").mkdir()
        (tmp_path / "place" / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\nnot really")
        with pytest.raises(InputError, match=r"broken\.png"):
            load_images([tmp_path], CAMERA)

    def test_scikit_images_photographs_are_found(self) -> None:
        assert len(skimage_paths()) == 11


class TestPairs:
    def test_a_view_of_the_same_picture_is_accepted(self) -> None:
        # The control: the test can accept. A 6 px shift is a small turn of the camera.
        brick = _skimage("brick.png")
        shifted = ChanceImage("copy/brick.png", "copy", np.roll(brick.image, 6, axis=1))
        (outcome,) = try_pairs([brick, shifted], CAMERA, CONFIG)
        assert outcome.verification.accepted, outcome

    def test_images_of_one_set_are_not_paired(self) -> None:
        a, b = _skimage("coffee.png"), _skimage("coins.png")
        same = ChanceImage("x/coins.png", a.group, b.image)
        assert try_pairs([a, same], CAMERA, CONFIG) == []

    def test_unrelated_photographs_are_refused(self) -> None:
        images = [_skimage(n) for n in ("brick.png", "gravel.png", "grass.png", "text.png",
                                        "coins.png", "astronaut.png")]
        outcomes = try_pairs(images, CAMERA, CONFIG)
        result = summary(images, outcomes)
        assert result["pairs"] == 15
        assert result["accepted"] == 0, result["accepted_pairs"]
        assert result["max_inliers"] < CONFIG.localize.min_inliers


@needs_realdata
@pytest.mark.slow
def test_the_benchmark_meets_its_target(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "chance"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["sets"]["catadioptric"] == 18 and result["sets"]["skimage"] == 11
    assert result["pairs"] > 250
    assert result["accepted"] == 0
    assert result["paper_front_end"]["front_end"] == "harris-zncc"
    assert result["paper_front_end"]["accepted"] == 0
    assert result["targets_met"] == {"accepted": True, "paper_front_end.accepted": True}
    assert [t.figure for t in targets_of("chance")] == ["accepted", "paper_front_end.accepted"]
