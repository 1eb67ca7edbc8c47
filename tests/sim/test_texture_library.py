"""The texture library: the built-in set, a user's own set, and bad manifests."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import cv2
import numpy as np
import pytest

from shared.errors import ConfigError
from sim.texture_library import KINDS, Texture, TextureLibrary
from tools.textures.seamless import seam_ratio

TEXTURES = Path(__file__).resolve().parents[2] / "sim" / "textures"
MANIFEST = TEXTURES / "textures.toml"
LICENCES = {"CC0-1.0", "GPL-3.0-or-later", "LicenseRef-public-domain", "CC-BY-3.0",
            "CC-BY-3.0-US"}


@pytest.fixture(scope="module")
def builtin() -> TextureLibrary:
    return TextureLibrary.builtin()


def _manifest() -> dict[str, dict[str, object]]:
    with MANIFEST.open("rb") as f:
        return tomllib.load(f)


class TestBuiltin:
    def test_every_texture_loads_as_contiguous_grey(self, builtin: TextureLibrary) -> None:
        names = builtin.names()
        assert names == tuple(sorted(_manifest()))
        for name in names:
            texture = builtin.get(name)
            assert isinstance(texture, Texture)
            assert texture.name == name
            assert texture.image.dtype == np.uint8 and texture.image.ndim == 2
            assert texture.image.flags.c_contiguous
            assert texture.kind in KINDS
            assert all(math.isfinite(v) and v > 0 for v in texture.size_m)
            # Not a flat fill: a texture has texture.
            assert texture.image.std() > 3.0, name

    def test_is_cached(self, builtin: TextureLibrary) -> None:
        assert TextureLibrary.builtin() is builtin

    def test_images_are_read_only(self, builtin: TextureLibrary) -> None:
        image = builtin.get(builtin.names()[0]).image
        with pytest.raises(ValueError, match="read-only"):
            image[0, 0] = 0

    def test_px_per_m_is_pixels_over_size(self, builtin: TextureLibrary) -> None:
        texture = builtin.get("brick_wall")
        h, w = texture.image.shape
        assert texture.px_per_m == pytest.approx((w / texture.size_m[0], h / texture.size_m[1]))

    def test_names_by_kind(self, builtin: TextureLibrary) -> None:
        walls = builtin.names("wall")
        assert "brick_wall" in walls and "grass" not in walls
        assert all(builtin.get(n).kind == "wall" for n in walls)
        with pytest.raises(ConfigError, match="unknown texture kind 'roof'"):
            builtin.names("roof")

    def test_unknown_name_is_an_error_naming_it(self, builtin: TextureLibrary) -> None:
        with pytest.raises(ConfigError, match=r"textures\.toml: unknown texture 'brik_wall' "
                                              r"\(\d+ textures; did you mean brick_wall"):
            builtin.get("brik_wall")
        with pytest.raises(ConfigError, match=r"unknown texture 'zzz' .*see its names\(\)"):
            builtin.get("zzz")

    def test_tiling_textures_have_no_seam(self, builtin: TextureLibrary) -> None:
        # The step across each wrap-around seam is no more abrupt than the most abrupt
        # line inside the picture (a raw photograph scores 1.7 to 4.6 here).
        seams = {n: round(seam_ratio(builtin.get(n).image), 2) for n in builtin.names()
                 if builtin.get(n).tiles}
        assert {n: r for n, r in seams.items() if r > 1.05} == {}

    def test_every_file_has_its_source_and_a_licence_whose_text_is_vendored(self) -> None:
        manifest = _manifest()
        named = set()
        for name, entry in manifest.items():
            # An SPDX identifier, or several joined by AND (a picture made of several).
            for licence in str(entry["licence"]).split(" AND "):
                assert licence in LICENCES, name
                assert (TEXTURES / "LICENSES" / f"{licence}.txt").is_file()
            assert len(str(entry["source"])) > 10, name
            if "file" in entry:
                named.add(entry["file"])
        pictures = {p.name for p in TEXTURES.iterdir() if p.suffix in (".jpg", ".png")}
        assert pictures == named  # no picture without a manifest entry

    def test_covers_every_kind_with_several_textures(self, builtin: TextureLibrary) -> None:
        counts = {kind: len(builtin.names(kind)) for kind in KINDS}
        assert {k: n for k, n in counts.items() if n < 2} == {}
        assert len(builtin.names()) >= 35
        photographs = [n for n, e in _manifest().items() if "file" in e
                       and "drawn by" not in str(e["source"])]
        assert len(photographs) > len(builtin.names()) / 2

    def test_vendored_data_is_under_20_mb(self) -> None:
        total = sum(p.stat().st_size for p in TEXTURES.rglob("*") if p.is_file())
        assert total < 20e6


def _write(tmp_path: Path, body: str) -> Path:
    manifest = tmp_path / "textures.toml"
    manifest.write_text(body)
    return manifest


GOOD_ENTRY = """
[{name}]
file = "{file}"
size_m = [0.5, 0.25]
tiles = true
kind = "wall"
source = "made by the test"
licence = "CC0-1.0"
"""


class TestLoad:
    def test_a_users_own_set(self, tmp_path: Path) -> None:
        image = (np.arange(200 * 100) % 251).astype(np.uint8).reshape(100, 200)
        cv2.imwrite(str(tmp_path / "mine.png"), image)
        library = TextureLibrary.load(_write(tmp_path, GOOD_ENTRY.format(name="mine",
                                                                         file="mine.png")))
        texture = library.get("mine")
        np.testing.assert_array_equal(texture.image, image)
        assert texture.size_m == (0.5, 0.25)
        assert texture.px_per_m == (400.0, 400.0)
        assert texture.tiles and texture.kind == "wall"

    def test_a_procedural_entry(self, tmp_path: Path) -> None:
        manifest = _write(tmp_path, """
[boards]
procedural = "wood_grain"
size_m = [1.0, 0.5]
kind = "floor"
tiles = true
source = "procedural"
licence = "CC0-1.0"
params = { seed = 7, width_px = 256, height_px = 128, rings = 5 }
""")
        texture = TextureLibrary.load(manifest).get("boards")
        assert texture.image.shape == (128, 256)

    @pytest.mark.parametrize(("body", "message"), [
        (GOOD_ENTRY.format(name="a", file="a.png") + "colour = 3\n",
         r"\[a\]: unknown key 'colour'"),
        (GOOD_ENTRY.format(name="a", file="missing.png"),
         r"\[a\]: file missing.png: cannot read the image"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace("[0.5, 0.25]", "[0.5, 0.0]"),
         r"\[a\]: size_m must be two finite numbers > 0"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace("[0.5, 0.25]", "[-1, 0.25]"),
         r"\[a\]: size_m must be two finite numbers > 0"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace("[0.5, 0.25]", "[nan, 0.25]"),
         r"\[a\]\.size_m\[0\]: expected a finite number"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace("[0.5, 0.25]", "[inf, 0.25]"),
         r"\[a\]\.size_m\[0\]: expected a finite number"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace('"wall"', '"roof"'),
         r"\[a\]: unknown kind 'roof'"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace('file = "a.png"',
                                                           'procedural = "bricks"'),
         r"\[a\]: unknown procedural generator 'bricks'"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace('file = "a.png"', ""),
         r"\[a\]: give exactly one of 'file' and 'procedural'"),
        (GOOD_ENTRY.format(name="a", file="a.png").replace('file = "a.png"',
                                                           'procedural = "carpet"')
         + "params = { pile = 3 }\n", r"\[a\]\.params: unknown key 'pile'"),
        (GOOD_ENTRY.format(name="a", file="a.png") + "params = { seed = 3 }\n",
         r"\[a\]: 'params' is for a procedural texture only"),
        ("", r"no texture in the manifest"),
        ("a = 3\n", r"\[a\]: expected a table"),
    ])
    def test_bad_manifest_is_one_line_naming_file_and_entry(
            self, tmp_path: Path, body: str, message: str) -> None:
        cv2.imwrite(str(tmp_path / "a.png"), np.full((8, 8), 100, np.uint8))
        manifest = _write(tmp_path, body)
        with pytest.raises(ConfigError, match=message) as info:
            TextureLibrary.load(manifest)
        text = str(info.value)
        assert text.startswith(str(manifest)) and "\n" not in text

    def test_a_file_that_does_not_decode(self, tmp_path: Path) -> None:
        (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 40)
        (tmp_path / "text.jpg").write_text("not a picture")
        for file in ("broken.png", "text.jpg"):
            manifest = _write(tmp_path, GOOD_ENTRY.format(name="bad", file=file))
            with pytest.raises(ConfigError, match=rf"\[bad\]: file {file}: ") as info:
                TextureLibrary.load(manifest)
            assert "\n" not in str(info.value)

    def test_missing_manifest(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match="file not found"):
            TextureLibrary.load(tmp_path / "none.toml")
