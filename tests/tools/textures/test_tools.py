"""The texture set's contact sheet and measurement, on a small set of the test's own."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from sim.texture_library import TextureLibrary
from tools.textures import contact_sheet, measure


@pytest.fixture
def small_set(tmp_path: Path, rng: np.random.Generator) -> Path:
    cv2.imwrite(str(tmp_path / "poster.png"), rng.integers(0, 255, (60, 40), dtype=np.uint8))
    manifest = tmp_path / "textures.toml"
    manifest.write_text("""
[poster]
file = "poster.png"
size_m = [0.4, 0.6]
kind = "picture"
source = "the test"
licence = "CC0-1.0"

[boards]
procedural = "wood_grain"
size_m = [1.0, 1.0]
tiles = true
kind = "floor"
source = "the test"
licence = "CC0-1.0"
params = { width_px = 64, height_px = 64 }
""")
    return manifest


def test_contact_sheet_has_a_cell_per_texture(small_set: Path) -> None:
    sheet = contact_sheet.contact_sheet(TextureLibrary.load(small_set))
    cell = contact_sheet.CELL_PX
    assert sheet.shape == (cell + contact_sheet.LABEL_PX, contact_sheet.COLUMNS * cell)
    # Two cells drawn (floor first, by kind), the rest of the row blank.
    assert sheet[:cell, :2 * cell].std() > 10
    assert np.all(sheet[:cell, 2 * cell:] == 255)


def test_contact_sheet_command_writes_a_png(small_set: Path, tmp_path: Path) -> None:
    out = tmp_path / "sheet.png"
    assert contact_sheet.main([str(out), "--manifest", str(small_set)]) == 0
    assert cv2.imread(str(out), cv2.IMREAD_GRAYSCALE) is not None


def test_measure_gives_the_figures(small_set: Path) -> None:
    # measure() itself: main() would pin the test's process to one core.
    figures = json.loads(json.dumps(measure.measure(small_set, 2)))
    assert figures["textures"] == 2 and figures["tiling"] == 1
    assert figures["by_kind"]["picture"] == 1 and figures["by_kind"]["floor"] == 1
    assert len(figures["load_s"]) == 2 and figures["load_s_median"] > 0
    assert figures["px_per_m_min"] == 64.0  # the boards: 64 px over 1 m
    assert figures["seam_ratio_max"] <= 1.0
    # The poster is random noise: corners all over it; the boards' rings give fewer.
    assert figures["corners_per_m2_median_by_kind"]["picture"] > 100
    assert set(figures["corners_per_m2_fewest"]) == {"poster", "boards"}


def test_measure_refuses_no_repeats(capsys: pytest.CaptureFixture[str]) -> None:
    assert measure.main(["--repeats", "0"]) == 2
    assert "--repeats: must be >= 1" in capsys.readouterr().err
