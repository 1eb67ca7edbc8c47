"""The texture set's build: its manifest matches the catalogue, its readers parse their formats."""

from __future__ import annotations

import struct
import tomllib
import zipfile
from pathlib import Path

import cv2
import numpy as np
import pytest

from sim.texture_library import KINDS
from tools.textures.build import DEFAULT_OUT, manifest_table
from tools.textures.catalogue import RECIPES
from tools.textures.sources import Sources


def test_the_vendored_manifest_is_the_catalogues() -> None:
    # Rebuilding the set from tools/textures/catalogue.py gives the committed manifest:
    # an edit to one without the other fails here.
    with (DEFAULT_OUT / "textures.toml").open("rb") as f:
        vendored = tomllib.load(f)
    rebuilt = tomllib.loads("\n".join(manifest_table(r) for r in RECIPES))
    assert rebuilt == vendored


def test_recipes_are_unique_and_valid() -> None:
    names = [r.name for r in RECIPES]
    assert len(names) == len(set(names))
    for recipe in RECIPES:
        assert recipe.kind in KINDS
        assert (recipe.make is None) == (recipe.procedural is not None), recipe.name
        assert recipe.ext in ("jpg", "png")


def test_manifest_table_quotes_strings() -> None:
    recipe = next(r for r in RECIPES if r.procedural is not None)
    table = tomllib.loads(manifest_table(recipe))[recipe.name]
    assert table["procedural"] == recipe.procedural
    assert table["params"] == dict(recipe.params)
    assert table["size_m"] == list(recipe.size_m)


def _pattern_file(path: Path, pixels: np.ndarray, name: bytes = b"Test\0") -> None:
    h, w, depth = pixels.shape
    header = struct.pack(">5I", 24 + len(name), 1, w, h, depth) + b"GPAT" + name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(header + pixels.tobytes())


class TestSources:
    def test_gimp_pattern_rgb_and_grey(self, tmp_path: Path) -> None:
        folder = tmp_path / "gimp-data" / "usr/share/gimp/2.0/patterns"
        rgb = np.zeros((3, 4, 3), np.uint8)
        rgb[..., 0] = 255  # pure red
        _pattern_file(folder / "Test" / "red.pat", rgb)
        grey = np.arange(12, dtype=np.uint8).reshape(3, 4, 1)
        _pattern_file(folder / "Test" / "grey.pat", grey)
        sources = Sources(tmp_path)
        red = sources.gimp_pattern("Test/red.pat")
        assert red.shape == (3, 4)
        assert np.all(red == cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY))
        assert 70 <= int(red[0, 0]) <= 80  # red's luma, 0.299 * 255
        np.testing.assert_array_equal(sources.gimp_pattern("Test/grey.pat"), grey[..., 0])

    def test_gimp_pattern_bad_magic(self, tmp_path: Path) -> None:
        path = tmp_path / "gimp-data" / "usr/share/gimp/2.0/patterns" / "bad.pat"
        _pattern_file(path, np.zeros((2, 2, 1), np.uint8))
        data = bytearray(path.read_bytes())
        data[20:24] = b"XXXX"
        path.write_bytes(bytes(data))
        with pytest.raises(ValueError, match="not a GIMP pattern"):
            Sources(tmp_path).gimp_pattern("bad.pat")

    def test_sweethome3d_member(self, tmp_path: Path) -> None:
        folder = tmp_path / "sweethome3d-furniture" / "usr/share/sweethome3d/furniture"
        folder.mkdir(parents=True)
        image = (np.arange(64).reshape(8, 8) * 3).astype(np.uint8)
        ok, png = cv2.imencode(".png", image)
        assert ok
        with zipfile.ZipFile(folder / "Lib.sh3f", "w") as z:
            z.writestr("lib/model/wood.png", png.tobytes())
            z.writestr("lib/model/broken.jpg", b"not a picture")
        sources = Sources(tmp_path)
        np.testing.assert_array_equal(sources.sweethome3d("Lib", "lib/model/wood.png"), image)
        with pytest.raises(ValueError, match="does not decode"):
            sources.sweethome3d("Lib", "lib/model/broken.jpg")
