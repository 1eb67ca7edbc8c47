"""``vmnav vision localize IMG --memory DIR`` (tools/vision_localize_cmd.py) on a memory
taught in the simulator (the lab's 2.5 m ``east_a`` route), with views rendered by
``vmnav sim snapshot``."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.camera_model import CameraModel
from tools.bench.chance import fitted_to_camera, skimage_paths
from tools.cli import main

pytestmark = pytest.mark.slow


def snapshot(world_file: Path, out: Path, x: float, y: float, yaw_deg: float) -> Path:
    code = main(["sim", "snapshot", "--world", str(world_file), "--seed", "1", "--out", str(out),
                 "--x", str(x), "--y", str(y), "--yaw", str(yaw_deg)])
    assert code == 0
    return out / "frame.png"


def localize(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(["vision", "localize", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_view_beside_the_route_is_localized(
    east_a: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world_file, memory = east_a
    image = snapshot(world_file, tmp_path / "q", 3.1, 10.15, 8.0)
    code, out, err = localize([str(image), "--memory", str(memory)], capsys)
    assert code == 0, err
    report = json.loads(out)
    assert report["ok"] and report["verdict"] == "accepted"
    best, *others = report["candidates"]
    assert best["keyframe_id"] == report["keyframe_id"] and best["path"] == "east_a"
    # The view is about 1.1 m along the route; key images come about 0.5 m apart.
    assert abs(best["distance_m"] - 1.1) <= 0.6
    assert best["inliers"] == report["inliers"] >= 20
    assert best["inlier_ratio"] >= 0.5 and abs(best["yaw_deg"]) < 20.0
    # Where a route from the view starts: this key image or the next one, which sees the
    # view behind it.
    ahead = next(c for c in report["candidates"] if c["keyframe_id"] == report["ahead_id"])
    assert ahead["path"] == "east_a" and ahead["index"] in (best["index"], best["index"] + 1)
    assert ahead is best or ahead["along"] < 0
    # Every candidate is verified; the answer (the walk along the path from the most
    # inliers, within 3 key images of it) first, then the others by inliers.
    assert all(c["verdict"] is not None for c in report["candidates"])
    ranked = [(c["verdict"] == "accepted", c["inliers"]) for c in others]
    assert ranked == sorted(ranked, reverse=True)
    most = max(report["candidates"], key=lambda c: c["inliers"])
    assert most["path"] == best["path"] and abs(most["index"] - best["index"]) <= 3
    assert len(others) == min(20, report["keyframes"]) - 1


def test_a_photograph_of_elsewhere_is_not_localized(
    east_a: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, memory = east_a
    (brick,) = [p for p in skimage_paths() if p.name == "brick.png"]
    photo = fitted_to_camera(cv2.imread(str(brick), cv2.IMREAD_GRAYSCALE),
                             CameraModel.default())
    path = tmp_path / "brick.png"
    cv2.imwrite(str(path), photo)
    code, out, _ = localize([str(path), "--memory", str(memory)], capsys)
    assert code == 0
    report = json.loads(out)
    assert not report["ok"] and report["verdict"] != "accepted"
    assert not any(c["verdict"] == "accepted" for c in report["candidates"])


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda p: p, "nothing.png: no such image file"),
        (lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n cut") and p, "cannot be decoded as an image"),
        (lambda p: cv2.imwrite(str(p), np.zeros((60, 80), np.uint8)) and p,
         "is 80x60 px; the memory's camera takes 800x600 px"),
    ],
)
def test_a_bad_image_is_one_line(
    east_a: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    make: object, message: str,
) -> None:
    _, memory = east_a
    image = make(tmp_path / "nothing.png")  # type: ignore[operator]
    code, out, err = localize([str(image), "--memory", str(memory)], capsys)
    assert code == 1 and out == ""
    assert err.startswith("vmnav vision: error: ") and message in err
    assert err.count("\n") == 1


def test_a_bad_memory_is_one_line(
    east_a: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world_file, _ = east_a
    image = snapshot(world_file, tmp_path / "q", 3.0, 10.0, 0.0)
    code, out, err = localize([str(image), "--memory", str(tmp_path / "none")], capsys)
    assert code == 1 and out == ""
    assert "manifest.json" in err and err.count("\n") == 1
