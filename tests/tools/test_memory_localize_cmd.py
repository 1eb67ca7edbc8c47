"""``vmnav memory localize --memory DIR IMAGE`` (tools/memory_localize_cmd.py) on a synthetic memory
on disk."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.memory import write_memory
from tests.robot.memory.textured import FEATURES, Place, make_places, memory_of
from tests.shared.memory.builders import small_camera
from tools.cli import main


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def places() -> list[Place]:
    return make_places(np.random.default_rng(11), 6, small_camera())


@pytest.fixture
def memory_dir(tmp_path: Path, places: list[Place]) -> Path:
    memory = memory_of(
        {"west": [p.key_image for p in places[:3]], "east": [p.key_image for p in places[3:]]}
    )
    write_memory(tmp_path / "mem", memory)
    # The memory's front end (the paper's, sized for the small lens), and a localization.
    features = (f'[features]\nmethod = "{FEATURES.method}"\n'
                f"patch_size_deg = {FEATURES.patch_size_deg!r}\n"
                f"min_distance_deg = {FEATURES.min_distance_deg!r}\n")
    (tmp_path / "features.toml").write_text(features)
    (tmp_path / "vmnav.toml").write_text(
        features + "[localize]\ncandidates = 3\nmin_inliers = 10\n")
    return tmp_path / "mem"


def query_file(folder: Path, image: np.ndarray, name: str = "query.png") -> Path:
    path = folder / name
    assert cv2.imwrite(str(path), image)
    return path


class TestLocalize:
    def test_prints_the_key_image_its_matches_and_the_time(
        self, memory_dir: Path, places: list[Place], capsys: pytest.CaptureFixture[str]
    ) -> None:
        query = query_file(memory_dir.parent, places[4].query)
        config = str(memory_dir.parent / "vmnav.toml")
        argv = ["memory", "localize", "--memory", str(memory_dir), str(query), "--config", config]
        code, out, err = run(argv, capsys)
        assert code == 0, err
        first, second = out.splitlines()
        assert first.startswith("key image 4 (path 1 'east', index 1, 0.50 m along): ")
        assert first.endswith(" verified inliers") and "not localized" not in first
        # The prefilter's 3 candidates and the walk's path neighbour beyond them.
        assert " ms for 6 key images (4 matched, " in second
        assert " verified; localizer built in " in second

    def test_json_and_the_exhaustive_baseline(
        self, memory_dir: Path, places: list[Place], capsys: pytest.CaptureFixture[str]
    ) -> None:
        query = query_file(memory_dir.parent, places[1].query)
        code, out, _ = run(
            ["memory", "localize", "--memory", str(memory_dir), str(query), "--exhaustive",
             "--json", "--config", str(memory_dir.parent / "features.toml")], capsys
        )
        assert code == 0
        report = json.loads(out)
        assert report["keyframe_id"] == 1 and report["keyframes"] == 6
        assert report["exhaustive"]["keyframe_id"] == 1
        assert report["exhaustive"]["matches"] == report["matches"]
        assert report["exhaustive"]["inliers"] == report["inliers"] > 0
        assert report["ok"] and report["verdict"] == "accepted"
        assert report["localize_ms"] > 0 and len(report["candidates"]) == 6
        best = report["candidates"][0]
        assert best["keyframe_id"] == 1 and best["path"] == "west" and best["index"] == 1
        assert best["inliers"] == report["inliers"] and best["verdict"] == "accepted"

    def test_an_image_of_nowhere_is_not_localized(
        self, memory_dir: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        other = make_places(np.random.default_rng(99), 1, small_camera())[0].query
        query = query_file(memory_dir.parent, other)
        config = str(memory_dir.parent / "vmnav.toml")
        code, out, _ = run(["memory", "localize", "--memory", str(memory_dir), str(query),
                            "--config", config], capsys)
        assert code == 0
        assert ": not localized)" in out.splitlines()[0]

    def test_a_colour_image_is_read_as_grey(
        self, memory_dir: Path, places: list[Place], capsys: pytest.CaptureFixture[str]
    ) -> None:
        colour = cv2.cvtColor(places[2].query, cv2.COLOR_GRAY2BGR)
        query = query_file(memory_dir.parent, colour)
        code, out, _ = run(["memory", "localize", "--memory", str(memory_dir), str(query), "--json",
                            "--config", str(memory_dir.parent / "features.toml")], capsys)
        assert code == 0 and json.loads(out)["keyframe_id"] == 2


class TestBadInput:
    @pytest.mark.parametrize(
        ("image", "message"),
        [
            (np.zeros((60, 80), np.uint8), "query.png: is 80x60 px; the memory's camera takes "
             "160x120 px"),
            (np.zeros((120, 160), np.uint16), "query.png: expected 8-bit pixels, got uint16"),
        ],
    )
    def test_the_wrong_image(
        self,
        memory_dir: Path,
        image: np.ndarray,
        message: str,
        capsys: pytest.CaptureFixture[str],
    ) -> None:
        query = query_file(memory_dir.parent, image)
        code, out, err = run(["memory", "localize", "--memory", str(memory_dir), str(query)],
                             capsys)
        assert code == 1 and out == ""
        assert err.startswith("vmnav memory: error: ") and message in err

    def test_a_missing_or_broken_image(
        self, memory_dir: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        missing = memory_dir.parent / "nothing.png"
        code, _, err = run(["memory", "localize", "--memory", str(memory_dir), str(missing)],
                           capsys)
        assert code == 1 and "nothing.png: no such image file" in err
        broken = memory_dir.parent / "broken.png"
        broken.write_bytes(b"\x89PNG\r\n\x1a\n truncated")
        code, _, err = run(["memory", "localize", "--memory", str(memory_dir), str(broken)], capsys)
        assert code == 1 and "broken.png: cannot be decoded as an image" in err

    def test_a_missing_memory(
        self, tmp_path: Path, places: list[Place], capsys: pytest.CaptureFixture[str]
    ) -> None:
        query = query_file(tmp_path, places[0].query)
        code, _, err = run(["memory", "localize", "--memory", str(tmp_path / "none"),
                            str(query)], capsys)
        assert code == 1 and "manifest.json" in err
