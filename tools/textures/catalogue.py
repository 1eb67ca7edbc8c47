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
from tools.textures.sources import (
    GIMP_WHERE,
    SKIMAGE_WHERE,
    SWEETHOME3D_WHERE,
    GreyImage,
    Sources,
)

CC0 = "CC0-1.0"
PD = "LicenseRef-public-domain"
GPL = "GPL-3.0-or-later"
CC_BY = "CC-BY-3.0"
CC_BY_US = "CC-BY-3.0-US"
DRAWN = "drawn by tools/textures/compose.py"
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


def _sh3d(library: str, member: str, note: str = "") -> str:
    credit = {"BlendSwap-CC-0": "",
              "Scopia": " (by Scopia Visual Interfaces Systems, s.l.)",
              "KatorLegaz": " (by Andrew Kator & Jennifer Legaz)"}[library]
    return f"{SWEETHOME3D_WHERE}{library}.sh3f, {member}{credit}" + (f"; {note}" if note else "")


_BS = "BlendSwap-CC-0"
_OAK = "blendswap-cc-0/islandExtension/american_oak.jpg"
_WOOD13 = "blendswap-cc-0/table/Wood_013_COLOR.jpg"
_METAL = "blendswap-cc-0/rangeHood/Metal009_2K_Color.jpg"
_TERRAZZO = "blendswap-cc-0/islandExtension/marble_14.jpg"
_BOOKS = tuple(f"katorlegaz/full-bookcase/books{i}.jpg" for i in (1, 2, 3, 4))


def _sh3d_tile(library: str, member: str, seamless: bool = True,
               box: tuple[int, int, int, int] | None = None,
               level: tuple[float, float] | None = None) -> Callable[[Sources], GreyImage]:
    """A Sweet Home 3D texture, cropped to ``box``, relevelled to (mean, std), made seamless."""

    def make(s: Sources) -> GreyImage:
        image = s.sweethome3d(library, member)
        if box is not None:
            image = compose.crop_resized(image, box)
        if level is not None:
            image = compose.relevel(image, *level)
        return make_seamless(image) if seamless else image

    return make


def _sh3d_picture(library: str, member: str, frame: bool = True) -> Callable[[Sources], GreyImage]:
    def make(s: Sources) -> GreyImage:
        image = s.sweethome3d(library, member)
        return compose.framed(image) if frame else image

    return make


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


def _oak(s: Sources) -> GreyImage:
    return make_seamless(s.sweethome3d(_BS, _OAK))


def _wood13(s: Sources) -> GreyImage:
    return make_seamless(s.sweethome3d(_BS, _WOOD13))


def _metal(s: Sources) -> GreyImage:
    return make_seamless(s.sweethome3d(_BS, _METAL))


def _sky(s: Sources) -> GreyImage:
    return s.gimp_pattern("Sky/sky.pat")


def _ceiling_tiles(s: Sources) -> GreyImage:
    return compose.ceiling_tiles(make_seamless(s.sweethome3d(_BS, _TERRAZZO)), 300, 2, _rng(11))


def _noticeboard(s: Sources) -> GreyImage:
    notices = [s.sweethome3d("KatorLegaz", "katorlegaz/newspaper/Newspaper.jpg"),
               s.skimage("text.png"), compose.printed_page(800, "NOTICE", _rng(12))]
    return compose.noticeboard(s.gimp_pattern("Wood/corkboard.pat"),
                               s.gimp_pattern("Paper/paper.pat"), notices, 600, _rng(13))


def _facade(wall: Callable[[Sources], GreyImage], windows: int, window_m: tuple[float, float],
            frame_level: int, seed: int) -> Callable[[Sources], GreyImage]:
    return lambda s: compose.facade(wall(s), _sky(s), 120, 6.0, 3.0, windows, window_m,
                                    frame_level, _rng(seed))


RECIPES: tuple[Recipe, ...] = (
    # Walls.
    Recipe("brick_wall", "wall", (1.0, 1.0), True, _gimp("Stone/brick.pat", "repeated 2 x 2"),
           GPL, _pattern("Stone/brick.pat", 2)),
    Recipe("stone_wall", "wall", (0.9, 0.57), True, _gimp("Stone/rock.pat", "repeated 2 x 2"),
           GPL, _pattern("Stone/rock.pat", 2)),
    Recipe("wood_panel_wall", "wall", (1.2, 1.2), True,
           _sh3d("Scopia", "scopia/jacuzzi/paneling-for-interior.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/jacuzzi/paneling-for-interior.jpg")),
    Recipe("wood_plank_wall", "wall", (1.2, 1.2), True,
           _sh3d("Scopia", "scopia/garden-hut/gardenHutTexture.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/garden-hut/gardenHutTexture.jpg")),
    Recipe("wood_grain_wall", "wall", (1.2, 1.2), True,
           _gimp("Wood/wood2.pat", "repeated 3 x 3"), GPL, _pattern("Wood/wood2.pat", 3)),
    Recipe("marble_tile_wall", "wall", (0.6, 0.6), True,
           _gimp("Stone/marble2.pat", "repeated 2 x 2"), GPL, _pattern("Stone/marble2.pat", 2)),
    Recipe("mosaic_tile_wall", "wall", (0.5, 0.5), True,
           _sh3d("Scopia", "scopia/swimming-pool/swimming-pool-tiles.jpg", "made seamless"),
           CC_BY, _sh3d_tile("Scopia", "scopia/swimming-pool/swimming-pool-tiles.jpg")),
    Recipe("plaster_wall", "wall", (1.0, 1.0), True,
           _sh3d("Scopia", "scopia/chimney/OcherTexture.jpg", "relevelled, made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/chimney/OcherTexture.jpg", level=(190.0, 8.0))),
    Recipe("plaster_wall_painted", "wall", (2.0, 2.0), True, PROC, CC0,
           procedural="plaster", params={"seed": 1}),
    Recipe("plaster_wall_dark", "wall", (2.0, 2.0), True, PROC, CC0,
           procedural="plaster", params={"seed": 14, "mean_level": 140.0, "contrast": 9.0}),
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
    Recipe("wood_plank_floor", "floor", (1.5, 1.0), True,
           _sh3d("Scopia", "scopia/contemp_living_room/big_brown_wood_tile.jpg", "made seamless"),
           CC_BY, _sh3d_tile("Scopia", "scopia/contemp_living_room/big_brown_wood_tile.jpg")),
    Recipe("marble_floor", "floor", (1.0, 1.0), True,
           _gimp("Stone/marble1.pat", "repeated 2 x 2"), GPL, _pattern("Stone/marble1.pat", 2)),
    Recipe("terrazzo_floor", "floor", (0.8, 0.8), True, _sh3d(_BS, _TERRAZZO, "made seamless"),
           CC0, _sh3d_tile(_BS, _TERRAZZO)),
    Recipe("slate_floor", "floor", (0.8, 0.8), True, _gimp("Stone/slate.pat"), GPL,
           _pattern("Stone/slate.pat")),
    Recipe("carpet_floor", "floor", (1.0, 1.0), True, PROC, CC0,
           procedural="carpet", params={"seed": 3}),
    Recipe("carpet_loop_floor", "floor", (0.5, 0.5), True,
           _sh3d(_BS, "blendswap-cc-0/couch/Plain001.jpg", "darkened, made seamless"), CC0,
           _sh3d_tile(_BS, "blendswap-cc-0/couch/Plain001.jpg", level=(90.0, 20.0))),
    Recipe("tile_floor", "floor", (1.2, 1.2), True, PROC, CC0,
           procedural="tile_grid", params={"seed": 4, "tiles_x": 4, "tiles_y": 4,
                                           "grout_px": 4, "tile_level": 170.0,
                                           "tile_variation": 18.0}),
    Recipe("rug", "floor", (1.4, 2.0), False,
           _sh3d("KatorLegaz", "katorlegaz/oriental-rug/rug.jpg"), CC_BY_US,
           _sh3d_picture("KatorLegaz", "katorlegaz/oriental-rug/rug.jpg", frame=False)),
    Recipe("grass", "floor", (1.5, 1.5), True, _sk("grass.png", "made seamless"), CC0,
           _photo_tile("grass.png")),
    Recipe("gravel", "floor", (1.0, 1.0), True, _sk("gravel.png", "made seamless"), CC0,
           _photo_tile("gravel.png")),
    Recipe("brick_paving", "floor", (1.0, 2.0), True,
           _sk("brick.png", "central 256 x 512 px, made seamless"), CC0,
           _photo_tile("brick.png", (128, 0, 256, 512))),
    Recipe("stone_paving", "floor", (1.2, 1.2), True,
           _gimp("Stone/stone33.pat", "repeated 2 x 2"), GPL, _pattern("Stone/stone33.pat", 2)),
    Recipe("asphalt", "floor", (1.0, 1.0), True,
           _sh3d(_BS, "blendswap-cc-0/rock2/rock02.jpg", "made seamless"), CC0,
           _sh3d_tile(_BS, "blendswap-cc-0/rock2/rock02.jpg")),
    Recipe("soil", "floor", (0.8, 0.8), True,
           _sh3d(_BS, "blendswap-cc-0/plantie/ground.jpg", "made seamless"), CC0,
           _sh3d_tile(_BS, "blendswap-cc-0/plantie/ground.jpg")),
    # Ceilings and lamps.
    Recipe("ceiling_tiles", "ceiling", (1.2, 1.2), True,
           _sh3d(_BS, _TERRAZZO, "relevelled as mineral tiles, T-bar grid drawn"), CC0,
           _ceiling_tiles),
    Recipe("ceiling_plaster", "ceiling", (2.0, 2.0), True, PROC, CC0,
           procedural="plaster", params={"seed": 15, "mean_level": 215.0, "contrast": 4.0}),
    Recipe("lamp_troffer", "lamp", (0.6, 1.2), False, DRAWN, CC0,
           lambda s: compose.ceiling_lamp(400, 0.6, 1.2, (2, 6)), ext="png"),
    Recipe("lamp_square", "lamp", (0.6, 0.6), False, DRAWN, CC0,
           lambda s: compose.ceiling_lamp(400, 0.6, 0.6, (3, 3)), ext="png"),
    Recipe("lamp_round", "lamp", (0.5, 0.5), False, DRAWN, CC0,
           lambda s: compose.round_lamp(400, 0.4, 0.05), ext="png"),
    # Doors.
    Recipe("door_wood", "door", (1.0, 2.1), False,
           _sh3d(_BS, _OAK, "four recessed panels drawn"), CC0,
           lambda s: compose.door(_oak(s), 300, 4)),
    Recipe("door_wood_glazed", "door", (1.0, 2.1), False,
           _sh3d(_BS, _WOOD13, "turned upright, two panels drawn, the upper glazed with ")
           + _gimp("Sky/sky.pat"), GPL,
           lambda s: compose.door(np.ascontiguousarray(np.rot90(_wood13(s))), 300, 2,
                                  glass=compose.glass(_sky(s), 200, 300, 215, _rng(16)))),
    Recipe("door_painted", "door", (1.0, 2.1), False,
           _sh3d("Scopia", "scopia/chimney/OcherTexture.jpg", "as paint; two panels drawn"),
           CC_BY, lambda s: compose.door(
               _oak(s), 300, 2,
               paint=compose.relevel(s.sweethome3d("Scopia", "scopia/chimney/OcherTexture.jpg"),
                                     215, 6))),
    Recipe("door_metal", "door", (1.0, 2.1), False, _sh3d(_BS, _METAL, "push bar drawn"), CC0,
           lambda s: compose.metal_door(_metal(s), 300)),
    Recipe("door_elevator", "door", (1.6, 1.6), False,
           _sh3d("Scopia", "scopia/elevator-door/elevator-door.jpg"), CC_BY,
           _sh3d_picture("Scopia", "scopia/elevator-door/elevator-door.jpg", frame=False)),
    Recipe("door_garage", "door", (2.5, 2.2), True,
           _sh3d("Scopia", "scopia/garage-door2/textureDoor.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/garage-door2/textureDoor.jpg")),
    Recipe("door_entrance_glass", "door", (2.0, 2.3), False,
           _sh3d(_BS, _METAL, "as the frames") + "; " + _gimp("Sky/sky.pat", "as the glass"),
           f"{CC0} AND {GPL}",
           lambda s: compose.glass_doors(_metal(s), compose.glass(_sky(s), 400, 460, 225,
                                                                   _rng(24)), 250)),
    # Windows (seen from inside: bright daylight through the glass).
    Recipe("window_bright", "window", (1.2, 1.4), False,
           _gimp("Sky/sky.pat", "as the glass; frame drawn"), GPL,
           lambda s: compose.window(_sky(s), 300, 1.2, 1.4, 2, 2, 150, 232, _rng(17))),
    Recipe("window_wide", "window", (2.0, 1.2), False,
           _gimp("Sky/sky.pat", "as the glass; frame drawn"), GPL,
           lambda s: compose.window(_sky(s), 250, 2.0, 1.2, 3, 1, 70, 238, _rng(18))),
    Recipe("window_tall", "window", (1.0, 2.0), False,
           _gimp("Sky/sky.pat", "as the glass; frame drawn"), GPL,
           lambda s: compose.window(_sky(s), 250, 1.0, 2.0, 1, 3, 135, 228, _rng(19))),
    # Furniture.
    Recipe("desk_top", "furniture", (1.6, 0.8), False, _sh3d(_BS, _WOOD13, "edge band drawn"),
           CC0, lambda s: compose.desk_top(_wood13(s), 300, 1.6, 0.8)),
    Recipe("desk_side", "furniture", (0.8, 0.72), False, _sh3d(_BS, _OAK, "edge band drawn"),
           CC0, lambda s: compose.desk_top(_oak(s), 300, 0.8, 0.72)),
    Recipe("bookshelf", "furniture", (1.0, 2.0), False,
           _sh3d("KatorLegaz", "katorlegaz/full-bookcase/books1.jpg ... books4.jpg")
           + "; wood: " + _sh3d(_BS, _OAK), CC_BY_US,
           lambda s: compose.bookshelf_photo(_oak(s), [s.sweethome3d("KatorLegaz", b)
                                                       for b in _BOOKS], 300)),
    Recipe("bookshelf_mixed", "furniture", (1.0, 2.0), False,
           _sh3d(_BS, _WOOD13, "books drawn"), CC0,
           lambda s: compose.bookshelf(_wood13(s), 300, _rng(20))),
    Recipe("cabinet_drawers", "furniture", (0.5, 0.7), False,
           _sh3d(_BS, _OAK, "drawers drawn"), CC0,
           lambda s: compose.cabinet(_oak(s), 400, 0.5, 0.7, 3)),
    Recipe("cabinet_doors", "furniture", (0.8, 0.9), False,
           _sh3d(_BS, _WOOD13, "doors drawn"), CC0,
           lambda s: compose.cabinet(_wood13(s), 300, 0.8, 0.9, 0)),
    Recipe("cabinet_metal", "furniture", (0.5, 1.3), False,
           _sh3d(_BS, _METAL, "filing drawers drawn"), CC0,
           lambda s: compose.cabinet(compose.relevel(_metal(s), 170, 12), 300, 0.5, 1.3, 4)),
    Recipe("whiteboard", "furniture", (1.8, 1.2), False, DRAWN, CC0,
           lambda s: compose.whiteboard(300, _rng(25)), ext="png"),
    Recipe("radiator", "furniture", (1.0, 0.6), False, _sh3d(_BS, _METAL, "painted, columns drawn"),
           CC0, lambda s: compose.radiator(_metal(s), 300, 1.0, 0.6)),
    Recipe("wood_oak", "furniture", (0.6, 0.6), True, _sh3d(_BS, _OAK, "made seamless"), CC0,
           _oak),
    Recipe("brushed_metal", "furniture", (0.4, 0.4), True, _sh3d(_BS, _METAL, "made seamless"),
           CC0, _metal),
    Recipe("leather", "furniture", (0.3, 0.3), True, _gimp("Animal/leather.pat",
                                                           "repeated 2 x 2"),
           GPL, _pattern("Animal/leather.pat", 2)),
    Recipe("upholstery", "furniture", (0.5, 0.5), True,
           _sh3d(_BS, "blendswap-cc-0/couch2/Fabric_011_COLOR.jpg", "made seamless"), CC0,
           _sh3d_tile(_BS, "blendswap-cc-0/couch2/Fabric_011_COLOR.jpg")),
    # Posters and pictures.
    Recipe("poster_astronaut", "picture", (0.6, 0.6), False,
           _sk("astronaut.png", "framed"), PD, _photo("astronaut.png")),
    Recipe("poster_rocket", "picture", (0.6, 0.6), False,
           _sk("rocket.jpg", "central crop, framed"), PD, _photo("rocket.jpg", (107, 0, 427, 427))),
    Recipe("poster_deep_field", "picture", (0.7, 0.62), False,
           _sk("hubble_deep_field.jpg", "framed"), PD, _photo("hubble_deep_field.jpg")),
    Recipe("picture_camera", "picture", (0.5, 0.5), False, _sk("camera.png", "framed"), CC0,
           _photo("camera.png")),
    Recipe("picture_cat", "picture", (0.6, 0.42), False, _sk("chelsea.png", "framed"), CC0,
           _photo("chelsea.png")),
    Recipe("picture_coffee", "picture", (0.6, 0.42), False, _sk("coffee.png", "framed"), CC0,
           _photo("coffee.png")),
    Recipe("picture_street", "picture", (0.4, 0.52), False,
           _sh3d("Scopia", "scopia/frame2/HoiAn.jpg", "framed"), CC_BY,
           _sh3d_picture("Scopia", "scopia/frame2/HoiAn.jpg")),
    Recipe("picture_castle", "picture", (0.4, 0.52), False,
           _sh3d("Scopia", "scopia/frame1/chambord.jpg", "framed"), CC_BY,
           _sh3d_picture("Scopia", "scopia/frame1/chambord.jpg")),
    Recipe("calendar", "picture", (0.3, 0.28), False,
           _sh3d(_BS, "blendswap-cc-0/kalender/kalender.jpg"), CC0,
           _sh3d_picture(_BS, "blendswap-cc-0/kalender/kalender.jpg", frame=False)),
    Recipe("noticeboard", "picture", (0.9, 0.6), False,
           _gimp("Wood/corkboard.pat and Paper/paper.pat") + "; "
           + _sh3d("KatorLegaz", "katorlegaz/newspaper/Newspaper.jpg") + "; "
           + _sk("text.png", "pinned sheets drawn"), f"{GPL} AND {CC_BY_US} AND {PD}",
           _noticeboard),
    # Signs and switches.
    Recipe("sign_exit", "sign", (0.4, 0.15), False, DRAWN, CC0,
           lambda s: compose.exit_sign(800), ext="png"),
    Recipe("sign_exit_arrow", "sign", (0.4, 0.14), False,
           _sh3d(_BS, "blendswap-cc-0/emergencySign/sign.jpg"), CC0,
           _sh3d_picture(_BS, "blendswap-cc-0/emergencySign/sign.jpg", frame=False)),
    Recipe("sign_fire_extinguisher", "sign", (0.15, 0.3), False,
           _sh3d(_BS, "blendswap-cc-0/fireExtinguisher/label.jpg"), CC0,
           _sh3d_picture(_BS, "blendswap-cc-0/fireExtinguisher/label.jpg", frame=False)),
    *(Recipe(f"sign_room_{number}", "sign", (0.2, 0.1), False, DRAWN, CC0,
             (lambda n, lab: lambda s: compose.room_sign(1200, n, lab))(number, label),
             ext="png")
      for number, label in (("101", "Lab"), ("102", "Office"), ("103", "Meeting"),
                            ("104", "Library"), ("105", "Storage"), ("106", "Kitchen"))),
    Recipe("notice_text", "sign", (0.45, 0.17), False, _sk("text.png"), PD,
           lambda s: s.skimage("text.png"), ext="png"),
    Recipe("light_switch", "sign", (0.12, 0.12), False, DRAWN, CC0,
           lambda s: compose.light_switch(1000, 1), ext="png"),
    Recipe("light_switch_double", "sign", (0.12, 0.12), False, DRAWN, CC0,
           lambda s: compose.light_switch(1000, 2), ext="png"),
    # Outdoor facades: one storey, 6 m wide, repeating along and up the wall.
    Recipe("facade_brick", "facade", (6.0, 3.0), True,
           _gimp("Stone/brick.pat and Sky/sky.pat", "windows drawn"), GPL,
           _facade(lambda s: cv2.resize(s.gimp_pattern("Stone/brick.pat"), (60, 60),
                                        interpolation=cv2.INTER_AREA), 3, (1.2, 1.4), 215, 21)),
    Recipe("facade_concrete", "facade", (6.0, 3.0), True,
           _sh3d(_BS, "blendswap-cc-0/rock3/rock03.jpg", "relevelled as concrete") + "; "
           + _gimp("Sky/sky.pat", "windows drawn"), f"{CC0} AND {GPL}",
           _facade(lambda s: cv2.resize(make_seamless(compose.relevel(
               s.sweethome3d(_BS, "blendswap-cc-0/rock3/rock03.jpg"), 165, 14)), (180, 180),
               interpolation=cv2.INTER_AREA), 2, (2.0, 1.5), 60, 22)),
    Recipe("facade_wood", "facade", (6.0, 3.0), True,
           _sh3d("Scopia", "scopia/garden-hut/gardenHutTexture.jpg") + "; "
           + _gimp("Sky/sky.pat", "windows drawn"), f"{CC_BY} AND {GPL}",
           _facade(lambda s: cv2.resize(make_seamless(s.sweethome3d(
               "Scopia", "scopia/garden-hut/gardenHutTexture.jpg")), (120, 120),
               interpolation=cv2.INTER_AREA), 3, (1.0, 1.3), 235, 23)),
    # Trees.
    Recipe("tree_bark", "tree", (0.4, 0.44), True, _gimp("Wood/bark.pat"), GPL,
           _pattern("Wood/bark.pat")),
    Recipe("tree_bark_cypress", "tree", (0.6, 0.6), True,
           _sh3d("Scopia", "scopia/cypress/cypressTrunk.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/cypress/cypressTrunk.jpg")),
    Recipe("tree_bark_gnarled", "tree", (0.5, 0.28), True,
           _sh3d("Scopia", "scopia/bonsai-tree/bark.jpg", "turned upright, made seamless"),
           CC_BY, lambda s: make_seamless(np.ascontiguousarray(np.rot90(
               s.sweethome3d("Scopia", "scopia/bonsai-tree/bark.jpg"))))),
    Recipe("foliage", "tree", (0.5, 0.5), True, _gimp("Plant/leaves.pat", "repeated 2 x 2"),
           GPL, _pattern("Plant/leaves.pat", 2)),
    Recipe("foliage_cypress", "tree", (1.0, 1.0), True,
           _sh3d("Scopia", "scopia/cypress/cypressLeaves.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/cypress/cypressLeaves.jpg")),
    Recipe("hedge", "tree", (1.0, 1.0), True,
           _sh3d("Scopia", "scopia/hedgeTextured/hedge-displacement-texture.jpg",
                 "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/hedgeTextured/hedge-displacement-texture.jpg")),
    # People.
    Recipe("person_face", "person", (0.2, 0.227), False,
           _sk("astronaut.png", "the head, 150 x 170 px"), PD,
           lambda s: compose.crop_resized(s.skimage("astronaut.png"), (150, 10, 150, 170))),
    Recipe("skin", "person", (0.06, 0.06), True, _sk("astronaut.png", "a cheek, made seamless"),
           PD, lambda s: make_seamless(compose.crop_resized(s.skimage("astronaut.png"),
                                                            (243, 110, 20, 20), (80, 80)))),
    Recipe("hair", "person", (0.3, 0.3), True,
           _sh3d("Scopia", "scopia/mannequinBrunette/BrownHair.jpg", "made seamless"), CC_BY,
           _sh3d_tile("Scopia", "scopia/mannequinBrunette/BrownHair.jpg")),
    Recipe("clothing_suit", "person", (0.3, 0.45), True,
           _sk("astronaut.png", "the suit's fabric, made seamless"), PD,
           _photo_tile("astronaut.png", (40, 270, 80, 120), (160, 240))),
    Recipe("clothing_denim", "person", (0.2, 0.2), True,
           _sh3d(_BS, "blendswap-cc-0/chairWithCushion/Denim_001_COLOR.jpg", "made seamless"),
           CC0, _sh3d_tile(_BS, "blendswap-cc-0/chairWithCushion/Denim_001_COLOR.jpg")),
    Recipe("clothing_knit", "person", (0.25, 0.25), True,
           _sh3d(_BS, "blendswap-cc-0/chair/tecido.jpg", "made seamless"), CC0,
           _sh3d_tile(_BS, "blendswap-cc-0/chair/tecido.jpg")),
    Recipe("clothing_plain", "person", (0.4, 0.4), True, PROC, CC0,
           procedural="clothing", params={"seed": 5, "width_px": 256, "height_px": 256}),
    Recipe("clothing_striped", "person", (0.4, 0.4), True, PROC, CC0,
           procedural="clothing", params={"seed": 6, "width_px": 256, "height_px": 256,
                                          "stripes": 8, "mean_level": 140.0}),
    Recipe("clothing_checked", "person", (0.4, 0.4), True, PROC, CC0,
           procedural="clothing", params={"seed": 7, "width_px": 256, "height_px": 256,
                                          "stripes": 6, "checks": 6, "mean_level": 110.0,
                                          "stripe_contrast": 30.0}),
)
