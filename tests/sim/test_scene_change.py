"""sim.scene_change: each change does what it says, and the changed world stays drivable."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from shared.camera_model import CameraModel
from shared.pose import Pose2
from sim._geometry import box_corners, point_segment_distances
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer
from sim.scene_change import (
    KEEP_CLEAR_M,
    MOVE_MAX_M,
    TURN_MAX_DEG,
    LightingChange,
    SceneChange,
    change_world,
    relit_world,
)
from sim.simulation import Simulation
from sim.world import CLEARANCE_M, Box, Route, World, load_world
from tests.sim.rooms import box_room


def furnished_room() -> World:
    """A 10 x 6 m room, a route along y = 3, four boxes near the walls."""
    room = box_room()
    boxes = (Box((2.0, 0.8), (1.2, 0.6), 0.0, 0.75), Box((5.0, 0.8), (1.2, 0.6), 0.0, 0.75),
             Box((3.0, 5.2), (1.6, 0.5), 0.0, 1.8), Box((7.5, 5.2), (0.8, 0.8), 20.0, 0.9))
    route = Route("middle", ((1.0, 3.0), (9.0, 3.0)))
    return dataclasses.replace(room, furniture=boxes, routes=(route,),
                               start=Pose2(1.0, 3.0, 0.0))


def route_gap_m(world: World) -> float:
    """Least distance from the routes' legs to any furniture edge, m (independent of
    World's own check)."""
    corners = world.furniture_corners()
    gaps = []
    for route in world.routes:
        points = np.asarray(route.waypoints, dtype=float)
        for p, q in itertools.pairwise(points):
            samples = p + np.linspace(0.0, 1.0, 400)[:, None] * (q - p)
            a, b = corners.reshape(-1, 2), np.roll(corners, -1, axis=1).reshape(-1, 2)
            gaps.append(point_segment_distances(samples, a, b).min())
    return min(gaps)


class TestLighting:
    def test_scale_multiplies_the_brightness(self) -> None:
        world = furnished_room()
        assert relit_world(world, 0.5).lighting.brightness == world.lighting.brightness * 0.5
        assert relit_world(world, 1.0) is world

    def test_a_scale_beyond_the_range_names_the_world(self) -> None:
        with pytest.raises(ValueError, match=r"brightness 330 of world 'room' leave \(0, 255\)"):
            relit_world(furnished_room(), 3.0)

    def test_the_step_applies_from_its_time_on(self) -> None:
        light = LightingChange(step_factor=0.4, step_at_s=2.5)
        assert light.gain_at(0) == light.gain_at(2_499_999_999) == 1.0
        assert light.gain_at(2_500_000_000) == light.gain_at(10**12) == 0.4
        assert light.has_step and not LightingChange().has_step

    @pytest.mark.parametrize(("fields", "message"), [
        ({"scale": 0.0}, "scale must be > 0"),
        ({"scale": math.nan}, "scale must be > 0"),
        ({"step_factor": -1.0}, "step factor must be > 0"),
        ({"step_at_s": -2.0}, "step time must be >= 0 s"),
    ])
    def test_values_are_checked(self, fields: dict[str, float], message: str) -> None:
        with pytest.raises(ValueError, match=message):
            LightingChange(**fields)

    def test_the_rendered_scene_follows_the_step(self) -> None:
        config = dataclasses.replace(SimConfig(), render=dataclasses.replace(
            SimConfig().render, noise_sigma=0.0, illumination_amplitude=0.0))
        sim = Simulation(furnished_room(), config)
        sim.light_gain_at = LightingChange(step_factor=0.5, step_at_s=0.05).gain_at
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        before = renderer.render(sim).image.astype(float)
        sim.step_until(100_000_000)
        after = renderer.render(sim).image.astype(float)
        lit = before > 20
        assert np.median(after[lit] / before[lit]) == pytest.approx(0.5, abs=0.02)


class TestMovedObjects:
    def test_the_fraction_moves_within_the_bounds_and_the_rest_stays(self) -> None:
        world = furnished_room()
        changed = change_world(world, SceneChange(moved_fraction=0.5), np.random.default_rng(3))
        assert len(changed.moved) + len(changed.stuck) == 2 and len(changed.moved) >= 1
        for i, (old, new) in enumerate(zip(world.furniture, changed.world.furniture,
                                           strict=True)):
            if i in changed.moved:
                assert new != old and new.size == old.size and new.height_m == old.height_m
                assert math.dist(new.center, old.center) <= MOVE_MAX_M
                assert abs(new.yaw_deg - old.yaw_deg) <= TURN_MAX_DEG
            else:
                assert new == old

    @pytest.mark.parametrize("seed", range(6))
    def test_the_route_stays_clear(self, seed: int) -> None:
        changed = change_world(furnished_room(), SceneChange(moved_fraction=1.0),
                               np.random.default_rng(seed))
        assert changed.moved
        assert route_gap_m(changed.world) >= CLEARANCE_M
        assert World(**{f.name: getattr(changed.world, f.name)
                        for f in dataclasses.fields(World)}) == changed.world  # validates

    @pytest.mark.parametrize("seed", range(4))
    def test_moved_objects_stay_inside_and_apart(self, seed: int) -> None:
        changed = change_world(furnished_room(), SceneChange(moved_fraction=1.0),
                               np.random.default_rng(seed))
        corners = changed.world.furniture_corners()
        assert (corners > 0.05).all() and (corners[..., 0] < 9.95).all()
        assert (corners[..., 1] < 5.95).all()
        sim = Simulation(changed.world, SimConfig())  # pymunk accepts the layout
        assert sim.free_space.is_reachable(np.array([[9.0, 3.0]])).all()

    def test_points_kept_clear_stay_clear(self) -> None:
        keep = np.array([[2.0, 1.6], [5.0, 1.6]])  # just beside the two low boxes
        for seed in range(5):
            changed = change_world(furnished_room(), SceneChange(moved_fraction=1.0),
                                   np.random.default_rng(seed), keep)
            for box in changed.world.furniture:
                corners = box_corners(box.center, box.size, box.yaw_deg)
                edges = point_segment_distances(keep, corners, np.roll(corners, -1, axis=0))
                original = box in furnished_room().furniture
                assert original or edges.min() >= KEEP_CLEAR_M

    def test_an_object_with_no_place_stays_and_is_counted(self) -> None:
        everywhere = np.array([[x, y] for x in np.arange(0.0, 10.1, 0.5)
                               for y in np.arange(0.0, 6.1, 0.5)])
        world = furnished_room()
        changed = change_world(world, SceneChange(moved_fraction=1.0),
                               np.random.default_rng(0), everywhere)
        assert changed.moved == () and changed.stuck == (0, 1, 2, 3)
        assert changed.world == world

    def test_the_same_seed_gives_the_same_world(self) -> None:
        change = SceneChange(moved_fraction=0.5)
        a = change_world(furnished_room(), change, np.random.default_rng(7))
        b = change_world(furnished_room(), change, np.random.default_rng(7))
        assert a == b

    def test_a_world_without_objects_refuses(self) -> None:
        with pytest.raises(ValueError, match="world 'room' has no movable objects"):
            change_world(box_room(), SceneChange(moved_fraction=0.2), np.random.default_rng(0))

    @pytest.mark.parametrize("fraction", [-0.1, 1.5, math.nan])
    def test_the_fraction_is_checked(self, fraction: float) -> None:
        with pytest.raises(ValueError, match=r"moved fraction must be in \[0, 1\]"):
            SceneChange(moved_fraction=fraction)

    def test_a_fifth_of_the_lab_moves_and_its_routes_stay_clear(self) -> None:
        lab = load_world("lab")
        changed = change_world(lab, SceneChange(moved_fraction=0.2), np.random.default_rng(1))
        assert len(changed.moved) + len(changed.stuck) == round(0.2 * len(lab.furniture))
        assert len(changed.moved) >= len(changed.stuck)
        assert route_gap_m(changed.world) >= CLEARANCE_M


def test_no_change_is_the_same_world() -> None:
    world = furnished_room()
    changed = change_world(world, SceneChange(), np.random.default_rng(0))
    assert changed.world is world and changed.moved == changed.stuck == ()
    assert SceneChange().is_none and not SceneChange(moved_fraction=0.1).is_none
