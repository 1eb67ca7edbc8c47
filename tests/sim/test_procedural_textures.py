"""Procedural textures: seeded, seamless, of the asked size, with their parameters checked."""

from __future__ import annotations

import numpy as np
import pytest

from shared.config import from_mapping
from shared.errors import ConfigError
from sim.procedural_textures import (
    GENERATORS,
    TileGridParams,
    WoodGrainParams,
    periodic_noise,
    tile_grid,
    wood_grain,
)
from tools.textures.seamless import seam_ratio


@pytest.mark.parametrize("name", sorted(GENERATORS))
class TestEveryGenerator:
    def test_size_type_and_contiguity(self, name: str) -> None:
        params_cls, generate = GENERATORS[name]
        image = generate(params_cls(width_px=192, height_px=128, seed=3))
        assert image.shape == (128, 192) and image.dtype == np.uint8
        assert image.flags.c_contiguous
        assert image.std() > 3.0  # textured, not flat

    def test_same_seed_same_picture_other_seed_other_picture(self, name: str) -> None:
        params_cls, generate = GENERATORS[name]
        a = generate(params_cls(seed=1, width_px=128, height_px=128))
        b = generate(params_cls(seed=1, width_px=128, height_px=128))
        c = generate(params_cls(seed=2, width_px=128, height_px=128))
        np.testing.assert_array_equal(a, b)
        assert np.abs(a.astype(int) - c.astype(int)).mean() > 1.0

    def test_tiles_seamlessly(self, name: str) -> None:
        params_cls, generate = GENERATORS[name]
        for seed in range(3):
            assert seam_ratio(generate(params_cls(seed=seed, width_px=256,
                                                  height_px=128))) <= 1.0

    def test_unknown_parameter_is_a_config_error(self, name: str) -> None:
        params_cls, _ = GENERATORS[name]
        with pytest.raises(ConfigError, match=r"m\.toml: \[t\]\.params: unknown key 'bogus'"):
            from_mapping(params_cls, {"bogus": 1}, "m.toml", "[t].params")


class TestPeriodicNoise:
    def test_unit_std_zero_mean_and_periodic(self) -> None:
        noise = periodic_noise((128, 96), 3.0, np.random.default_rng(0))
        assert noise.shape == (128, 96)
        assert abs(noise.mean()) < 1e-9 and noise.std() == pytest.approx(1.0)
        # Neighbours across the wrap are as alike as neighbours inside.
        inside = np.abs(np.diff(noise, axis=1)).mean()
        across = np.abs(noise[:, 0] - noise[:, -1]).mean()
        assert across < 1.5 * inside

    def test_scale_sets_the_correlation_length(self) -> None:
        rng = np.random.default_rng(1)
        fine = periodic_noise((256, 256), 1.0, rng)
        coarse = periodic_noise((256, 256), 8.0, rng)
        assert np.abs(np.diff(coarse, axis=1)).mean() < 0.3 * np.abs(np.diff(fine, axis=1)).mean()


class TestTileGrid:
    def test_grout_lines_lie_on_the_tile_pitch(self) -> None:
        p = TileGridParams(width_px=256, height_px=256, tiles_x=4, tiles_y=4, grout_px=6,
                           grout_level=60.0, tile_level=200.0, tile_variation=0.0, speckle=0.0)
        image = tile_grid(p)
        column_means = image.mean(axis=0)
        dark = np.flatnonzero(column_means < 100)
        # Grout centred on x = 0, 64, 128, 192 (and the wrap): 3 px each side.
        assert set(dark) == {x % 256 for c in (0, 64, 128, 192, 256) for x in range(c - 3, c + 3)}

    def test_grout_wider_than_half_a_tile_is_refused(self) -> None:
        with pytest.raises(ConfigError, match="grout_px"):
            from_mapping(TileGridParams, {"tiles_x": 8, "width_px": 64, "grout_px": 5}, "m", "t")


class TestWoodGrain:
    def test_rings_run_along_x(self) -> None:
        image = wood_grain(WoodGrainParams(width_px=256, height_px=256, rings=8, warp_px=0.0,
                                           fibre_contrast=0.0)).astype(np.float64)
        # Without warp the rings are straight lines along x: rows are flat, columns vary.
        assert image.std(axis=1).mean() < 1.0
        assert image.std(axis=0).mean() > 10.0

    def test_sizes_out_of_range_are_refused(self) -> None:
        with pytest.raises(ConfigError, match=r"width_px and height_px must be in 16\.\.4096"):
            from_mapping(WoodGrainParams, {"width_px": 8}, "m", "t")
        with pytest.raises(ConfigError, match="rings must be >= 1"):
            from_mapping(WoodGrainParams, {"rings": 0}, "m", "t")
