"""Procedural grey textures: wood grain, carpet, tiles with grout, plaster, clothing.

A complement to the photographs of :mod:`sim.textures`: surfaces whose look is mostly
a statistic (carpet pile, plaster) or a regular layout (a tile grid) are generated
here, seeded, so a world can ask for a variant the photographs do not have. Every
generator returns an (H, W) uint8 picture that **tiles seamlessly**: its noise is
white noise filtered in the Fourier domain (periodic by construction) and its
structures (rings, grout lines, weave) have a whole number of periods across the
picture.

A manifest entry names a generator with ``procedural = "<name>"`` and gives its
parameters in a ``params`` table (the fields of the generator's parameter class,
:data:`GENERATORS`); unknown parameters are errors (:func:`shared.config.from_mapping`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from shared.config import require

GreyImage = npt.NDArray[np.uint8]  # (H, W) uint8
_FloatImage = npt.NDArray[np.float64]  # (H, W) float64


@dataclass(frozen=True, slots=True)
class _Size:
    """The picture's size and seed, common to every generator."""

    width_px: int = 512
    """Width of the picture, px (16..4096)."""
    height_px: int = 512
    """Height of the picture, px (16..4096)."""
    seed: int = 0
    """Seed of the picture's noise (same seed, same picture)."""

    def __post_init__(self) -> None:
        require(16 <= self.width_px <= 4096 and 16 <= self.height_px <= 4096,
                f"width_px and height_px must be in 16..4096, got "
                f"{self.width_px} x {self.height_px}")


def periodic_noise(shape: tuple[int, int], scale_px: float | tuple[float, float],
                   rng: np.random.Generator) -> _FloatImage:
    """Smooth noise that tiles seamlessly, zero mean, unit standard deviation.

    White noise filtered with a Gaussian of standard deviation ``scale_px`` by
    multiplying its discrete Fourier transform (a circular convolution, hence
    periodic with the picture's size). The white noise is drawn in the Fourier
    domain (complex Gaussian coefficients: the transform of white noise), which
    saves the forward transform.

    Args:
        shape: (H, W) of the result, px.
        scale_px: correlation length of the noise, px (> 0); or (along y, along x)
            for noise stretched along one axis (fibres).
        rng: the source of the white noise.

    Returns:
        (H, W) float64 noise.
    """
    h, w = shape
    fy = np.fft.fftfreq(h).astype(np.float32)[:, None]
    fx = np.fft.rfftfreq(w).astype(np.float32)[None, :]
    # A Gaussian of std s px has the transform exp(-2 pi^2 s^2 f^2), f in cycles/px.
    sy, sx = scale_px if isinstance(scale_px, tuple) else (scale_px, scale_px)
    gain = np.exp(np.float32(-2.0 * np.pi**2) * ((sx * fx) ** 2 + (sy * fy) ** 2))
    spectrum = np.empty(gain.shape, np.complex64)
    spectrum.real = rng.standard_normal(gain.shape, np.float32)
    spectrum.imag = rng.standard_normal(gain.shape, np.float32)
    noise = np.fft.irfft2(spectrum * gain, s=(h, w)).astype(np.float64)
    noise -= noise.mean()
    std = noise.std()
    return noise / std if std > 0 else noise


def _to_uint8(image: _FloatImage) -> GreyImage:
    return np.ascontiguousarray(np.clip(np.rint(image), 0, 255).astype(np.uint8))


@dataclass(frozen=True, slots=True)
class WoodGrainParams(_Size):
    """Wood grain along x: growth rings seen edge-on, warped, with fine fibres."""

    rings: int = 9
    """Growth rings across the picture's height (a whole number, so it tiles)."""
    mean_level: float = 120.0
    """Mean grey level, 0..255."""
    ring_contrast: float = 35.0
    """Amplitude of the rings, grey levels."""
    warp_px: float = 14.0
    """How far the rings wander up and down, px."""
    fibre_contrast: float = 10.0
    """Standard deviation of the fine fibres along the grain, grey levels."""

    def __post_init__(self) -> None:
        _Size.__post_init__(self)
        require(self.rings >= 1, f"rings must be >= 1, got {self.rings}")


def wood_grain(p: WoodGrainParams) -> GreyImage:
    """A plank's face: rings along x (sharp late wood, soft early wood) and fibres.

    Returns:
        (height_px, width_px) uint8, seamless.
    """
    rng = np.random.default_rng(p.seed)
    shape = (p.height_px, p.width_px)
    y = np.arange(p.height_px, dtype=np.float64)[:, None]
    warp = p.warp_px * periodic_noise(shape, p.width_px / 6.0, rng)
    phase = 2.0 * np.pi * p.rings * (y + warp) / p.height_px
    # Late wood is a narrow dark band: a raised cosine sharpened by a power.
    rings = ((1.0 + np.cos(phase)) / 2.0) ** 4
    fibres = periodic_noise(shape, (0.7, p.width_px / 24.0), rng)  # long along x
    image = p.mean_level + p.ring_contrast * (0.5 - rings) + p.fibre_contrast * fibres
    return _to_uint8(image)


@dataclass(frozen=True, slots=True)
class CarpetParams(_Size):
    """Loop-pile carpet: fine speckle over a faint mottle."""

    mean_level: float = 95.0
    """Mean grey level, 0..255."""
    pile_contrast: float = 22.0
    """Standard deviation of the pile's speckle, grey levels."""
    mottle_contrast: float = 8.0
    """Standard deviation of the large-scale mottle, grey levels."""
    pile_px: float = 1.2
    """Size of a tuft, px."""


def carpet(p: CarpetParams) -> GreyImage:
    """Returns (height_px, width_px) uint8, seamless."""
    rng = np.random.default_rng(p.seed)
    shape = (p.height_px, p.width_px)
    image = (p.mean_level + p.pile_contrast * periodic_noise(shape, p.pile_px, rng)
             + p.mottle_contrast * periodic_noise(shape, min(shape) / 10.0, rng))
    return _to_uint8(image)


@dataclass(frozen=True, slots=True)
class TileGridParams(_Size):
    """Square tiles with grout lines, each tile a little different."""

    tiles_x: int = 4
    """Tiles across the picture's width."""
    tiles_y: int = 4
    """Tiles across the picture's height."""
    grout_px: int = 6
    """Width of a grout line, px."""
    tile_level: float = 200.0
    """Mean grey level of a tile, 0..255."""
    tile_variation: float = 12.0
    """Standard deviation of a tile's level from tile to tile, grey levels."""
    grout_level: float = 110.0
    """Grey level of the grout."""
    speckle: float = 5.0
    """Standard deviation of the glaze's and grout's fine noise, grey levels."""

    def __post_init__(self) -> None:
        _Size.__post_init__(self)
        require(self.tiles_x >= 1 and self.tiles_y >= 1,
                f"tiles_x and tiles_y must be >= 1, got {self.tiles_x}, {self.tiles_y}")
        require(1 <= self.grout_px < min(self.width_px // self.tiles_x,
                                         self.height_px // self.tiles_y) // 2,
                f"grout_px must be >= 1 and under half a tile, got {self.grout_px}")


def tile_grid(p: TileGridParams) -> GreyImage:
    """Tiles with grout lines centred on the picture's borders (so repeats join).

    Returns:
        (height_px, width_px) uint8, seamless.
    """
    rng = np.random.default_rng(p.seed)
    shape = (p.height_px, p.width_px)
    x = np.arange(p.width_px)
    y = np.arange(p.height_px)
    col = (x * p.tiles_x) // p.width_px
    row = (y * p.tiles_y) // p.height_px
    levels = p.tile_level + p.tile_variation * rng.standard_normal((p.tiles_y, p.tiles_x))
    image = levels[row[:, None], col[None, :]]
    # Distance to the nearest tile edge, px; half the grout on each side of an edge.
    pitch_x = p.width_px / p.tiles_x
    pitch_y = p.height_px / p.tiles_y
    dx = np.abs(((x + 0.5) % pitch_x) - pitch_x / 2.0)
    dy = np.abs(((y + 0.5) % pitch_y) - pitch_y / 2.0)
    in_grout = ((pitch_x / 2.0 - dx)[None, :] < p.grout_px / 2.0) | (
        (pitch_y / 2.0 - dy)[:, None] < p.grout_px / 2.0)
    image = np.where(in_grout, p.grout_level, image)
    image = image + p.speckle * periodic_noise(shape, 1.0, rng)
    return _to_uint8(image)


@dataclass(frozen=True, slots=True)
class PlasterParams(_Size):
    """Painted plaster: low-contrast mottle at several scales."""

    mean_level: float = 185.0
    """Mean grey level, 0..255."""
    contrast: float = 7.0
    """Standard deviation of the mottle at each scale, grey levels."""
    scales_px: tuple[float, ...] = (1.0, 4.0, 24.0)
    """Correlation lengths of the mottle's octaves, px."""


def plaster(p: PlasterParams) -> GreyImage:
    """Returns (height_px, width_px) uint8, seamless."""
    rng = np.random.default_rng(p.seed)
    shape = (p.height_px, p.width_px)
    image = np.full(shape, p.mean_level)
    for scale in p.scales_px:
        image += p.contrast * periodic_noise(shape, scale, rng)
    return _to_uint8(image)


@dataclass(frozen=True, slots=True)
class ClothingParams(_Size):
    """Woven cloth: a twill weave, optionally striped or checked, with folds."""

    mean_level: float = 90.0
    """Mean grey level, 0..255."""
    weave_px: int = 4
    """Period of the weave's diagonal ribs, px (divides the picture's sides)."""
    weave_contrast: float = 10.0
    """Amplitude of the weave, grey levels."""
    stripes: int = 0
    """Vertical stripes across the width (0: plain)."""
    checks: int = 0
    """Horizontal stripes across the height, crossing the vertical ones (0: none)."""
    stripe_contrast: float = 40.0
    """Level difference of the stripes, grey levels."""
    fold_contrast: float = 14.0
    """Standard deviation of the soft shading of folds, grey levels."""

    def __post_init__(self) -> None:
        _Size.__post_init__(self)
        require(self.weave_px >= 2 and self.width_px % self.weave_px == 0
                and self.height_px % self.weave_px == 0,
                f"weave_px must be >= 2 and divide {self.width_px} and {self.height_px}, "
                f"got {self.weave_px}")
        require(self.stripes >= 0 and self.checks >= 0,
                f"stripes and checks must be >= 0, got {self.stripes}, {self.checks}")


def clothing(p: ClothingParams) -> GreyImage:
    """Returns (height_px, width_px) uint8, seamless."""
    rng = np.random.default_rng(p.seed)
    shape = (p.height_px, p.width_px)
    y, x = np.mgrid[0:p.height_px, 0:p.width_px]
    weave = np.cos(2.0 * np.pi * ((x + y) % p.weave_px) / p.weave_px)
    image = p.mean_level + p.weave_contrast * weave
    if p.stripes:
        image = image + p.stripe_contrast * (((x * 2 * p.stripes) // p.width_px) % 2 - 0.5)
    if p.checks:
        image = image + p.stripe_contrast * (((y * 2 * p.checks) // p.height_px) % 2 - 0.5)
    image = image + p.fold_contrast * periodic_noise(shape, min(shape) / 12.0, rng)
    image = image + 3.0 * periodic_noise(shape, 0.8, rng)
    return _to_uint8(image)


#: Each generator by name: its parameter class and its function.
GENERATORS: dict[str, tuple[type[Any], Callable[[Any], GreyImage]]] = {
    "wood_grain": (WoodGrainParams, wood_grain),
    "carpet": (CarpetParams, carpet),
    "tile_grid": (TileGridParams, tile_grid),
    "plaster": (PlasterParams, plaster),
    "clothing": (ClothingParams, clothing),
}
