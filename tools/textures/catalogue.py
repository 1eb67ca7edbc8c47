"""The built-in textures, one recipe each: where the picture comes from, how it is made.

Physical sizes (``size_m``, width and height of the whole picture) come from what the
picture shows: a brick is ~0.22 m long, a parquet block ~0.3 m, a door 0.9 x 2.0 m.
Photographs of patterns that repeat (``tiles = True``) are made seamless by
:func:`tools.textures.seamless.make_seamless` unless their source already tiles (GIMP's
patterns are drawn to tile).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from tools.textures import compose
from tools.textures.seamless import make_seamless
from tools.textures.sources import GIMP_WHERE, SKIMAGE_WHERE, GreyImage, Sources

CC0 = "CC0-1.0"
PD = "LicenseRef-public-domain"
GPL = "GPL-3.0-or-later"
PROC = "sim/procedural_textures.py (seeded, generated when the set is loaded)"


@dataclass(frozen=True)
class Recipe:
    """One texture of the built-in set.

    ``make`` builds the picture from the fetched packages; a procedural texture has no
    ``make`` and names its generator and parameters instead.
    """

    name: str
    kind: str
    size_m: tuple[float, float]
    tiles: bool
    source: str
    licence: str
    make: Callable[[Sources], GreyImage] | None = None
    ext: str = "jpg"
    procedural: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)

    @property
    def file_name(self) -> str:
        """The picture's file name in the set."""
        return f"{self.name}.{self.ext}"


def _sk(file: str, note: str = "") -> str:
    return SKIMAGE_WHERE + file + (f"; {note}" if note else "")


def _gimp(file: str, note: str = "") -> str:
    return GIMP_WHERE + file + (f"; {note}" if note else "")


def _pattern(file: str, repeat: int = 1) -> Callable[[Sources], GreyImage]:
    """A GIMP pattern (already seamless), repeated ``repeat`` x ``repeat`` times."""
    return lambda s: np.tile(s.gimp_pattern(file), (repeat, repeat))


def _photo_tile(file: str, box: tuple[int, int, int, int] | None = None,
                size: tuple[int, int] | None = None) -> Callable[[Sources], GreyImage]:
    """A scikit-image photograph, cropped to ``box`` (x, y, w, h), resized, made seamless."""

    def make(s: Sources) -> GreyImage:
        image = s.skimage(file)
        if box is not None:
            x, y, w, h = box
            image = image[y:y + h, x:x + w]
        if size is not None:
            image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
        return make_seamless(image)

    return make


def _photo(file: str, box: tuple[int, int, int, int] | None = None,
           frame: bool = True) -> Callable[[Sources], GreyImage]:
    """A scikit-image photograph as a framed picture (not tiling)."""

    def make(s: Sources) -> GreyImage:
        image = s.skimage(file)
        if box is not None:
            x, y, w, h = box
            image = image[y:y + h, x:x + w]
        return compose.framed(image) if frame else image

    return make


RECIPES: tuple[Recipe, ...] = (
    # Walls.
    Recipe("brick_wall", "wall", (1.0, 1.0), True, _gimp("Stone/brick.pat", "repeated 2 x 2"),
           GPL, _pattern("Stone/brick.pat", 2)),
    Recipe("stone_wall", "wall", (0.9, 0.57), True, _gimp("Stone/rock.pat", "repeated 2 x 2"),
           GPL, _pattern("Stone/rock.pat", 2)),
    Recipe("wood_panel_wall", "wall", (1.2, 1.2), True,
           _gimp("Wood/wood2.pat", "repeated 3 x 3"), GPL, _pattern("Wood/wood2.pat", 3)),
    Recipe("marble_tile_wall", "wall", (0.6, 0.6), True,
           _gimp("Stone/marble2.pat", "repeated 2 x 2"), GPL, _pattern("Stone/marble2.pat", 2)),
    Recipe("plaster_wall", "wall", (2.0, 2.0), True, PROC, CC0,
           procedural="plaster", params={"seed": 1}),
    Recipe("tile_wall", "wall", (0.6, 0.6), True, PROC, CC0,
           procedural="tile_grid", params={"seed": 2, "tiles_x": 4, "tiles_y": 4,
                                           "grout_px": 5, "tile_level": 215.0}),
    # Floors.
    Recipe("parquet_floor", "floor", (0.6, 0.6), True,
           _gimp("Wood/parque1.pat", "repeated 2 x 2"), GPL, _pattern("Wood/parque1.pat", 2)),
    Recipe("parquet_herringbone_floor", "floor", (0.5, 0.5), True,
           _gimp("Wood/parque3.pat", "repeated 2 x 2"), GPL, _pattern("Wood/parque3.pat", 2)),
    Recipe("wood_floor", "floor", (0.8, 0.8), True,
           _gimp("Wood/wood1.pat", "repeated 2 x 2"), GPL, _pattern("Wood/wood1.pat", 2)),
    Recipe("marble_floor", "floor", (1.0, 1.0), True,
           _gimp("Stone/marble1.pat", "repeated 2 x 2"), GPL, _pattern("Stone/marble1.pat", 2)),
    Recipe("slate_floor", "floor", (0.8, 0.8), True, _gimp("Stone/slate.pat"), GPL,
           _pattern("Stone/slate.pat")),
    Recipe("carpet_floor", "floor", (1.0, 1.0), True, PROC, CC0,
           procedural="carpet", params={"seed": 3}),
    Recipe("tile_floor", "floor", (1.2, 1.2), True, PROC, CC0,
           procedural="tile_grid", params={"seed": 4, "tiles_x": 4, "tiles_y": 4,
                                           "grout_px": 4, "tile_level": 170.0,
                                           "tile_variation": 18.0}),
    Recipe("grass", "floor", (1.5, 1.5), True, _sk("grass.png", "made seamless"), CC0,
           _photo_tile("grass.png")),
    Recipe("gravel", "floor", (1.0, 1.0), True, _sk("gravel.png", "made seamless"), CC0,
           _photo_tile("gravel.png")),
    Recipe("brick_paving", "floor", (1.0, 2.0), True,
           _sk("brick.png", "central 256 x 512 px, made seamless"), CC0,
           _photo_tile("brick.png", (128, 0, 256, 512))),
    Recipe("stone_paving", "floor", (1.2, 1.2), True,
           _gimp("Stone/stone33.pat", "repeated 2 x 2"), GPL, _pattern("Stone/stone33.pat", 2)),
    # Pictures and posters.
    Recipe("poster_astronaut", "picture", (0.6, 0.6), False,
           _sk("astronaut.png", "framed"), PD, _photo("astronaut.png")),
    Recipe("poster_rocket", "picture", (0.6, 0.9), False,
           _sk("rocket.jpg", "central crop, framed"), PD, _photo("rocket.jpg", (107, 0, 427, 427))),
    Recipe("picture_camera", "picture", (0.5, 0.5), False, _sk("camera.png", "framed"), CC0,
           _photo("camera.png")),
    Recipe("picture_cat", "picture", (0.6, 0.4), False, _sk("chelsea.png", "framed"), CC0,
           _photo("chelsea.png")),
    Recipe("picture_coffee", "picture", (0.6, 0.4), False, _sk("coffee.png", "framed"), CC0,
           _photo("coffee.png")),
    Recipe("poster_deep_field", "picture", (0.7, 0.61), False,
           _sk("hubble_deep_field.jpg", "framed"), PD, _photo("hubble_deep_field.jpg")),
    # Trees.
    Recipe("tree_bark", "tree", (0.4, 0.44), True, _gimp("Wood/bark.pat"), GPL,
           _pattern("Wood/bark.pat")),
    Recipe("foliage", "tree", (0.5, 0.5), True, _gimp("Plant/leaves.pat", "repeated 2 x 2"),
           GPL, _pattern("Plant/leaves.pat", 2)),
    # People.
    Recipe("clothing_plain", "person", (0.4, 0.4), True, PROC, CC0,
           procedural="clothing", params={"seed": 5, "width_px": 256, "height_px": 256}),
    Recipe("clothing_striped", "person", (0.4, 0.4), True, PROC, CC0,
           procedural="clothing", params={"seed": 6, "width_px": 256, "height_px": 256,
                                          "stripes": 8, "mean_level": 140.0}),
)
