"""The world format's textures, pictures, objects, lamps, trees and floor regions."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from shared.errors import ConfigError
from sim._world_checks import place_picture
from sim.decor import PlacedObject, Tree
from sim.world import load_world

# A 6 x 4 m room split by a wall at x = 3 with a 1.2 m door (y = 1.4..2.6), decorated.
DECORATED = """
name = "decorated"
start = { x_m = 1.0, y_m = 2.0, yaw_deg = 0.0 }
walls = [
    { start = [0.0, 0.0], end = [6.0, 0.0], height_m = 2.5, texture = "brick_wall", scale_m = 0.8 },
    { start = [6.0, 0.0], end = [6.0, 4.0], height_m = 2.5, left = "wood_panel_wall" },
    { start = [6.0, 4.0], end = [0.0, 4.0], height_m = 2.5 },
    { start = [0.0, 4.0], end = [0.0, 0.0], height_m = 2.5 },
    { start = [3.0, 0.0], end = [3.0, 1.4], height_m = 2.5 },
    { start = [3.0, 2.6], end = [3.0, 4.0], height_m = 2.5, right = "tile_wall" },
]
ceilings = [
    { min_corner = [0.0, 0.0], max_corner = [6.0, 4.0], height_m = 2.5, texture = "ceiling_tiles" },
]
lamps = [
    { center = [1.5, 2.0] },
    { center = [4.5, 2.0], texture = "lamp_square", size = [0.6, 0.6], on = false },
]
pictures = [
    { at = [1.5, 3.8], texture = "poster_rocket", height_m = 1.5, name = "rocket", movable = true },
    { at = [2.8, 3.2], texture = "light_switch", height_m = 1.1 },
    { at = [5.8, 1.0], texture = "window_wide", height_m = 1.4, size = [1.6, 1.0] },
]

[[furniture]]
center = [5.0, 3.5]
size = [1.2, 0.6]
yaw_deg = 0.0
height_m = 2.0
kind = "shelf"
front = "bookshelf_mixed"

[[objects]]
kind = "board"
center = [1.5, 0.5]
size = [1.2, 0.05]
height_m = 1.2
elevation_m = 0.6
movable = true
name = "whiteboard"

[[objects]]
kind = "door"
center = [3.0, 2.0]
size = [1.2, 0.04]
yaw_deg = 90.0
height_m = 2.1
open_deg = 90.0
hinge = "end"
texture = "door_wood_glazed"

[floor]
texture = "carpet_floor"
regions = [
    { polygon = [[3, 0], [6, 0], [6, 4], [3, 4]], texture = "parquet_floor", scale_m = 0.5 },
]

[[routes]]
name = "through_door"
waypoints = [[1.0, 2.0], [4.6, 2.0]]
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "world.toml"
    path.write_text(text)
    return path


def refusal(tmp_path: Path, text: str) -> str:
    """The one-line message of loading ``text`` (which must fail)."""
    with pytest.raises(ConfigError) as info:
        load_world(write(tmp_path, text))
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(str(tmp_path / "world.toml"))
    return message


class TestDecoratedWorld:
    def test_every_part_is_read(self, tmp_path: Path) -> None:
        world = load_world(write(tmp_path, DECORATED))
        assert world.walls[0].texture == "brick_wall" and world.walls[0].scale_m == 0.8
        assert world.walls[1].left == "wood_panel_wall" and world.walls[1].right == ""
        assert world.furniture[0].kind == "shelf"
        assert world.ceilings[0].texture == "ceiling_tiles"
        assert [lamp.on for lamp in world.lamps] == [True, False]
        assert world.pictures[0].movable and world.pictures[0].name == "rocket"
        assert world.objects[0].movable and world.objects[1].kind == "door"
        assert world.floor.regions[0].scale_m == 0.5
        assert world.floor.texture == "carpet_floor"

    def test_pictures_go_on_the_nearest_wall_face(self, tmp_path: Path) -> None:
        world = load_world(write(tmp_path, DECORATED))
        poster = place_picture(world.walls, world.pictures[0])
        assert (poster.wall, poster.side) == (2, 1)  # the north wall runs west: south is its left
        assert poster.along_m == pytest.approx(4.5)
        switch = place_picture(world.walls, world.pictures[1])
        assert (switch.wall, switch.side) == (5, 1)  # the wall at x = 3 runs north; x < 3 left

    def test_an_open_door_turns_about_its_hinge(self) -> None:
        door = PlacedObject("door", (3.0, 2.0), (1.2, 0.04), 2.1, yaw_deg=90.0,
                            open_deg=90.0, hinge="end")
        (cx, cy), _, yaw = door.footprint()
        assert (cx, cy) == pytest.approx((3.6, 2.6))  # hinge at (3, 2.6), leaf along +x
        assert yaw == pytest.approx(180.0)
        closed = PlacedObject("door", (3.0, 2.0), (1.2, 0.04), 2.1, yaw_deg=90.0)
        assert closed.footprint() == ((3.0, 2.0), (1.2, 0.04), 90.0)

    def test_a_closed_door_across_the_route_is_refused(self, tmp_path: Path) -> None:
        text = DECORATED.replace("open_deg = 90.0\n", "")
        assert "object 1 at (3.0, 2.0)" in refusal(tmp_path, text)

    def test_objects_and_trunks_are_obstacles(self, tmp_path: Path) -> None:
        tree = "trees = [{ at = [4.6, 2.2] }]\n"
        text = DECORATED.replace("\n[[furniture]]", tree + "\n[[furniture]]", 1)
        assert "tree 0 at (4.6, 2.2)" in refusal(tmp_path, text)


class TestRefusals:
    @pytest.mark.parametrize(("old", "new", "expected"), [
        ('texture = "brick_wall"', 'texture = "brik_wall"',
         "walls[0].texture: unknown texture 'brik_wall'"),
        ('left = "wood_panel_wall"', 'left = "nope"', "walls[1].left: unknown texture 'nope'"),
        ('front = "bookshelf_mixed"', 'front = "books"', "furniture[0].front: unknown texture"),
        ('texture = "parquet_floor"', 'texture = "parket"',
         "floor.regions[0].texture: unknown texture 'parket'"),
        ('texture = "poster_rocket"', 'texture = "poster_moon"',
         "pictures[0].texture: unknown texture 'poster_moon'"),
        ('texture = "door_wood_glazed"', 'texture = "door_oak"', "objects[1].texture: unknown"),
        ("scale_m = 0.8", "scale_m = 0.0", "walls[0]: scale_m must be a finite number > 0"),
        ("scale_m = 0.5", "scale_m = -1.0", "floor.regions[0]: scale_m must be"),
        ('kind = "board"', 'kind = "sofa"', "objects[0]: unknown object kind 'sofa'"),
        ('kind = "shelf"', 'kind = "bed"', "furniture[0]: unknown furniture kind 'bed'"),
        ("at = [1.5, 3.8]", "at = [1.5, 2.0]", "pictures[0]: at (1.5, 2.0) is 1.45 m from"),
        ("size = [1.6, 1.0]", "size = [6.0, 1.0]", "pictures[2]: 6.0 m wide"),
        ("height_m = 1.5, name", "height_m = 2.4, name", "pictures[0]: 0.6 m high"),
        ("center = [1.5, 2.0] }", "center = [9.5, 2.0] }", "lamps[0]: no ceiling above"),
    ])
    def test_one_line_naming_the_entry(
        self, tmp_path: Path, old: str, new: str, expected: str
    ) -> None:
        assert old in DECORATED
        assert expected in refusal(tmp_path, DECORATED.replace(old, new, 1))

    def test_a_texture_file_that_does_not_decode(self, tmp_path: Path) -> None:
        (tmp_path / "mine").mkdir()
        (tmp_path / "mine" / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\nnot a picture")
        (tmp_path / "mine" / "textures.toml").write_text(
            '[my_poster]\nfile = "broken.png"\nsize_m = [0.5, 0.5]\nkind = "picture"\n'
            'source = "drawn by me"\nlicence = "CC0-1.0"\n')
        text = 'texture_set = "mine/textures.toml"\n' + DECORATED.replace(
            '"poster_rocket"', '"my_poster"')
        with pytest.raises(ConfigError) as info:
            load_world(write(tmp_path, text))
        message = str(info.value)
        assert "\n" not in message
        assert "textures.toml" in message and "[my_poster]" in message
        assert "broken.png" in message

    def test_a_user_texture_set_adds_to_the_builtin_one(self, tmp_path: Path) -> None:
        import cv2
        import numpy as np

        (tmp_path / "mine").mkdir()
        cv2.imwrite(str(tmp_path / "mine" / "mine.png"),
                    np.random.default_rng(1).integers(0, 255, (64, 64), dtype=np.uint8))
        (tmp_path / "mine" / "textures.toml").write_text(
            '[my_poster]\nfile = "mine.png"\nsize_m = [0.5, 0.5]\nkind = "picture"\n'
            'source = "drawn by me"\nlicence = "CC0-1.0"\n')
        text = 'texture_set = "mine/textures.toml"\n' + DECORATED.replace(
            '"poster_rocket"', '"my_poster"')
        world = load_world(write(tmp_path, text))
        assert world.textures().get("my_poster").size_m == (0.5, 0.5)
        assert world.textures().get("brick_wall").kind == "wall"


class TestParts:
    def test_a_crown_reaching_the_floor_is_refused(self) -> None:
        with pytest.raises(ValueError, match="crown_radius_m"):
            Tree((0.0, 0.0), trunk_height_m=1.0, crown_radius_m=1.5)

    def test_open_deg_is_for_doors(self) -> None:
        with pytest.raises(ValueError, match="open_deg is for doors only"):
            PlacedObject("box", (0.0, 0.0), (1.0, 1.0), 1.0, open_deg=30.0)

    def test_a_door_at_rest_is_its_own_footprint(self) -> None:
        door = PlacedObject("door", (1.0, 1.0), (0.9, 0.04), 2.0, yaw_deg=30.0)
        assert door.footprint()[2] == pytest.approx(30.0)
        assert math.isclose(door.footprint()[0][0], 1.0)
