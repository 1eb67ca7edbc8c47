from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import ConfigError
from sim._geometry import point_segment_distances
from sim.world import (
    CLEARANCE_M,
    WALL_HALF_THICKNESS_M,
    Box,
    Ceiling,
    LandmarkDensity,
    Pose2,
    Route,
    Wall,
    builtin_world_names,
    load_world,
)
from tests.sim.rooms import box_room

# A 6 x 4 m room split by a wall at x = 3 with a 1.2 m door (y = 1.4..2.6), and a desk.
GOOD = """
name = "tiny"
description = "two rooms"
start = { x_m = 1.0, y_m = 2.0, yaw_deg = 0.0 }
walls = [
    { start = [0.0, 0.0], end = [6.0, 0.0], height_m = 2.5 },
    { start = [6.0, 0.0], end = [6.0, 4.0], height_m = 2.5 },
    { start = [6.0, 4.0], end = [0.0, 4.0], height_m = 2.5 },
    { start = [0.0, 4.0], end = [0.0, 0.0], height_m = 2.5 },
    { start = [3.0, 0.0], end = [3.0, 1.4], height_m = 2.5 },
    { start = [3.0, 2.6], end = [3.0, 4.0], height_m = 2.5 },
]
furniture = [{ center = [5.0, 3.3], size = [1.2, 0.6], yaw_deg = 0.0, height_m = 0.75 }]
ceilings = [{ min_corner = [0.0, 0.0], max_corner = [6.0, 4.0], height_m = 2.5 }]

[[routes]]
name = "through_door"
waypoints = [[1.0, 2.0], [5.0, 2.0]]
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "world.toml"
    path.write_text(text)
    return path


def polyline_distance(
    point: tuple[float, float], waypoints: tuple[tuple[float, float], ...]
) -> float:
    pts = np.asarray(waypoints, dtype=float)
    return float(point_segment_distances(np.asarray([point], dtype=float), pts[:-1], pts[1:]).min())


class TestBuiltinWorlds:
    def test_names(self) -> None:
        assert builtin_world_names() == ("building", "campus", "lab")

    @pytest.mark.parametrize("name", ["lab", "campus"])
    def test_loads_with_routes_that_join(self, name: str) -> None:
        world = load_world(name)
        assert world.name == name
        assert len(world.routes) >= 3
        # At least two routes join: one starts or ends on another.
        joins = [
            (a.name, b.name)
            for a in world.routes
            for b in world.routes
            if a is not b
            and min(
                polyline_distance(a.waypoints[0], b.waypoints),
                polyline_distance(a.waypoints[-1], b.waypoints),
            )
            < 0.5
        ]
        assert joins

    def test_lab_is_an_indoor_floor_of_30_by_20_m(self) -> None:
        world = load_world("lab")
        assert world.extent() == ((0.0, 0.0), (30.0, 20.0))
        assert [c.height_m for c in world.ceilings] == [2.6]
        assert len(world.furniture) >= 10

    def test_campus_is_sparser_brighter_and_roofed_only_over_the_corridor(self) -> None:
        lab, campus = load_world("lab"), load_world("campus")
        (x0, y0), (x1, y1) = campus.extent()
        assert (x1 - x0, y1 - y0) == (45.0, 20.0)
        assert len(campus.ceilings) == 1
        corridor = campus.ceilings[0]
        assert corridor.max_corner[1] - corridor.min_corner[1] == pytest.approx(3.0)
        assert corridor.max_corner[0] - corridor.min_corner[0] == pytest.approx(20.0)
        assert max(w.height_m for w in campus.walls) >= 8.0
        assert campus.lighting.brightness > lab.lighting.brightness

    def test_the_lab_is_textured_without_patches(self) -> None:
        lab = load_world("lab")
        assert lab.landmarks.wall_per_m2 == lab.landmarks.furniture_per_m2 == 0.0
        assert all(w.left and w.right for w in lab.walls)
        assert len(lab.lamps) >= 30 and len(lab.pictures) >= 40
        assert {p.texture for p in lab.pictures} >= {"whiteboard", "light_switch", "window_wide"}
        assert any(o.movable for o in lab.objects) and any(o.kind == "door" for o in lab.objects)

    def test_campus_has_textured_facades_trees_and_open_sky(self) -> None:
        campus = load_world("campus")
        facades = [w for w in campus.walls if w.height_m >= 8.0]
        assert len(facades) == 5
        assert all((w.left + w.right).count("facade_") == 1 for w in facades)
        assert len(campus.trees) == 4 and campus.landmarks.wall_per_m2 == 0.0

    def test_building_goes_from_a_corridor_out_through_a_door(self) -> None:
        building = load_world("building")
        route = building.routes[0].waypoints
        ceiling = building.ceilings[0]
        inside = [ceiling.min_corner[0] <= x <= ceiling.max_corner[0]
                  and ceiling.min_corner[1] <= y <= ceiling.max_corner[1] for x, y in route]
        assert inside[0] and not inside[-1]
        doors = [o for o in building.objects if o.kind == "door"]
        assert len(doors) == 2 and all(d.open_deg != 0 for d in doors)

    def test_route_start_pose_faces_the_second_waypoint(self) -> None:
        route = Route("r", ((1.0, 1.0), (1.0, 3.0)))
        assert route.start_pose() == Pose2(1.0, 1.0, math.radians(90.0))


class TestLoadWorld:
    def test_a_user_file_loads(self, tmp_path: Path) -> None:
        world = load_world(write(tmp_path, GOOD))
        assert world.name == "tiny"
        assert world.furniture[0] == Box((5.0, 3.3), (1.2, 0.6), 0.0, 0.75)
        assert world.routes[0].waypoints == ((1.0, 2.0), (5.0, 2.0))

    def test_the_start_heading_in_degrees_becomes_radians(self, tmp_path: Path) -> None:
        text = GOOD.replace("yaw_deg = 0.0 }", "yaw_deg = 30.0 }", 1)
        world = load_world(write(tmp_path, text))
        assert world.start == Pose2(1.0, 2.0, math.radians(30.0))

    def test_a_start_table_with_an_unknown_key_is_refused(self, tmp_path: Path) -> None:
        path = write(tmp_path, GOOD.replace("yaw_deg = 0.0 }", "yaw_rad = 0.0 }", 1))
        with pytest.raises(ConfigError, match="start: unknown key 'yaw_rad'"):
            load_world(path)

    def test_patch_sizes_per_element_and_default(self, tmp_path: Path) -> None:
        text = (
            GOOD.replace(
                'description = "two rooms"\n',
                'description = "two rooms"\nlandmarks = { patch_size_m = 0.25 }\n',
            )
            .replace("height_m = 2.5 },", "height_m = 2.5, patch_size_m = 0.7 },", 1)
            .replace("height_m = 0.75", "height_m = 0.75, patch_size_m = 0.3")
        )
        world = load_world(write(tmp_path, text))
        assert world.landmarks == LandmarkDensity(patch_size_m=0.25)
        assert [w.patch_size_m for w in world.walls] == [0.7] + [None] * 5
        assert world.furniture[0].patch_size_m == 0.3
        assert world.ceilings[0].patch_size_m is None
        plain = load_world(write(tmp_path, GOOD))
        assert plain.landmarks.patch_size_m == 0.15
        assert all(w.patch_size_m is None for w in plain.walls)

    def test_unknown_name(self) -> None:
        known = r"\(built-in: building, campus, lab"
        with pytest.raises(ConfigError, match=r"^moon: unknown world " + known):
            load_world("moon")

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match="file not found"):
            load_world(str(tmp_path / "nope.toml"))

    @pytest.mark.parametrize(
        ("old", "new", "problem"),
        [
            ('name = "tiny"\n', "", "missing required key 'name'"),
            ("description", "colour = 3\ndescription", "unknown key 'colour'"),
            (
                "height_m = 0.75",
                "height_m = nan",
                r"furniture\[0\].height_m: expected a finite number",
            ),
            ("end = [6.0, 0.0]", "end = [0.0, 0.0]", r"walls\[0\]: wall has zero length"),
            (
                "[6.0, 4.0], height_m = 2.5 },\n    { start = [6.0, 4.0]",
                "[6.0, 4.0], height_m = -1 },\n    { start = [6.0, 4.0]",
                "height_m must be > 0",
            ),
            (
                "x_m = 1.0, y_m = 2.0",
                "x_m = 3.0, y_m = 1.0",
                r"start pose \(3.0, 1.0\) is 0.00 m from wall 4",
            ),
            (
                "x_m = 1.0, y_m = 2.0",
                "x_m = 9.0, y_m = 2.0",
                "start pose .* is outside the walls' extent",
            ),
            (
                "[[1.0, 2.0], [5.0, 2.0]]",
                "[[1.0, 2.0], [5.0, 3.0]]",
                r"route 'through_door' waypoint 1 \(5.0, 3.0\) is 0.00 m from furniture 0",
            ),
            (
                "[[1.0, 2.0], [5.0, 2.0]]",
                "[[1.0, 1.0], [5.0, 1.0]]",
                "route 'through_door' leg 0->1 is 0.00 m from wall 4",
            ),
            ("[[1.0, 2.0], [5.0, 2.0]]", "[[1.0, 2.0]]", "needs at least 2 waypoints"),
            (
                "max_corner = [6.0, 4.0]",
                "max_corner = [6.0, -4.0]",
                "min_corner .* must be below max_corner",
            ),
            (
                'name = "through_door"',
                'name = "through_door"\nwaypoints = [[1.0, 2.0], [2.0, 2.0]]\n'
                '[[routes]]\nname = "through_door"',
                "route name 'through_door' is used twice",
            ),
            ("walls = [", "walls = [[", "not valid TOML"),
            (
                "end = [6.0, 0.0], height_m = 2.5",
                "end = [6.0, 0.0], height_m = 2.5, patch_size_m = 0",
                r"walls\[0\]: patch_size_m must be finite and > 0, got 0.0",
            ),
            (
                "end = [6.0, 0.0], height_m = 2.5",
                "end = [6.0, 0.0], height_m = 2.5, patch_size_m = inf",
                r"walls\[0\].patch_size_m: expected a finite number, got float inf",
            ),
            (
                "end = [6.0, 0.0], height_m = 2.5",
                'end = [6.0, 0.0], height_m = 2.5, patch_size_m = "big"',
                r"walls\[0\].patch_size_m: expected a finite number, got str 'big'",
            ),
            (
                'description = "two rooms"\n',
                'description = "two rooms"\nlandmarks = { patch_size_m = -0.5 }\n',
                "landmarks: patch_size_m must be finite and > 0, got -0.5",
            ),
            (
                "height_m = 0.75",
                "height_m = 0.75, patch_size_m = nan",
                r"furniture\[0\].patch_size_m: expected a finite number, got float nan",
            ),
            (
                "max_corner = [6.0, 4.0], height_m = 2.5",
                "max_corner = [6.0, 4.0], height_m = 2.5, patch_size_m = -1",
                r"ceilings\[0\]: patch_size_m must be finite and > 0, got -1.0",
            ),
        ],
    )
    def test_bad_file_names_the_file_and_the_problem(
        self, tmp_path: Path, old: str, new: str, problem: str
    ) -> None:
        assert old in GOOD
        path = write(tmp_path, GOOD.replace(old, new, 1))
        with pytest.raises(ConfigError, match=f"^{path}: .*{problem}") as info:
            load_world(path)
        assert "\n" not in str(info.value)

    def test_unreachable_waypoint(self, tmp_path: Path) -> None:
        # Close the door: the second room can no longer be reached from the start.
        text = GOOD.replace("end = [3.0, 1.4]", "end = [3.0, 2.6]").replace(
            "waypoints = [[1.0, 2.0], [5.0, 2.0]]",
            "waypoints = [[1.0, 2.0], [2.0, 2.0]]\n"
            '[[routes]]\nname = "beyond"\nwaypoints = [[4.0, 1.0], [5.0, 1.0]]',
        )
        path = write(tmp_path, text)
        with pytest.raises(
            ConfigError, match=r"route 'beyond' waypoint 0 \(4.0, 1.0\) is not reachable"
        ):
            load_world(path)


class TestWorldDataclass:
    @settings(max_examples=60, deadline=None)
    @given(x=st.floats(0.0, 4.0), y=st.floats(0.0, 3.0))
    def test_start_is_accepted_exactly_when_clear_of_the_walls(self, x: float, y: float) -> None:
        gap = min(x, 4.0 - x, y, 3.0 - y) - WALL_HALF_THICKNESS_M
        if gap >= CLEARANCE_M + 1e-9:
            assert box_room((4.0, 3.0), Pose2(x, y)).start == Pose2(x, y)
        elif gap < CLEARANCE_M - 1e-9:
            with pytest.raises(ValueError, match="start pose"):
                box_room((4.0, 3.0), Pose2(x, y))

    def test_non_finite_values_are_refused(self) -> None:
        with pytest.raises(ValueError, match="finite"):
            Wall((0.0, math.nan), (1.0, 0.0), 2.0)
        refused = "patch_size_m must be finite and > 0, got "
        with pytest.raises(ValueError, match=refused + "nan"):
            Wall((0.0, 0.0), (1.0, 0.0), 2.0, patch_size_m=math.nan)
        with pytest.raises(ValueError, match=refused + "inf"):
            Box((0.0, 0.0), (1.0, 1.0), 0.0, 1.0, patch_size_m=math.inf)
        with pytest.raises(ValueError, match=re.escape(refused + "0.0")):
            Ceiling((0.0, 0.0), (1.0, 1.0), 2.0, patch_size_m=0.0)
        with pytest.raises(ValueError, match=re.escape(refused + "-0.1")):
            LandmarkDensity(patch_size_m=-0.1)
        with pytest.raises(ValueError, match="start pose must be finite"):
            box_room((4.0, 3.0), Pose2(1.0, 1.0, math.nan))
