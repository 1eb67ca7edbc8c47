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
from sim._object_moves import KEEP_CLEAR_M, MOVE_MAX_M, TURN_MAX_DEG
from sim.config import SensorConfig, SimConfig
from sim.decor import Lamp, Picture, PlacedObject
from sim.renderer import FisheyeRenderer
from sim.scene_change import (
    TEACH_HOUR,
    LightingChange,
    SceneChange,
    change_world,
    daylight_at,
)
from sim.simulation import Simulation
from sim.world import (
    CLEARANCE_M,
    Ceiling,
    Route,
    Wall,
    World,
    builtin_world_names,
    load_world,
)


def office() -> World:
    """A 10 x 6 m room split at x = 6 by a wall with a 1.2 m doorway (y = 2.4..3.6) and
    its door, open; a route along y = 3 through it; lamps, posters, movable things."""
    corners = [(0.0, 0.0), (10.0, 0.0), (10.0, 6.0), (0.0, 6.0)]
    walls = tuple(Wall(a, b, 2.5) for a, b in zip(corners, corners[1:] + corners[:1],
                                                 strict=True))
    walls += (Wall((6.0, 0.0), (6.0, 2.4), 2.5), Wall((6.0, 3.6), (6.0, 6.0), 2.5))
    lamps = tuple(Lamp((x, y)) for x in (2.0, 4.5, 8.0) for y in (1.5, 4.5))
    pictures = (
        Picture((2.0, 5.8), "poster_rocket", 1.5, name="rocket", movable=True),
        Picture((4.0, 5.8), "poster_astronaut", 1.5, movable=True),
        Picture((3.0, 0.2), "picture_cat", 1.5, movable=True),
        Picture((8.0, 0.2), "sign_exit", 2.0, name="exit"),
    )
    objects = (
        PlacedObject("box", (1.5, 0.8), (0.5, 0.5), 0.8, movable=True, name="bin"),
        PlacedObject("board", (4.0, 5.0), (1.2, 0.05), 1.2, elevation_m=0.6, movable=True,
                     name="whiteboard"),
        PlacedObject("box", (8.5, 5.0), (0.6, 0.6), 0.9, yaw_deg=20.0, movable=True),
        PlacedObject("box", (8.0, 1.0), (0.8, 0.6), 0.75),
        PlacedObject("door", (6.0, 3.0), (1.2, 0.04), 2.0, yaw_deg=90.0, name="door",
                     open_deg=90.0),
    )
    return World(name="office", walls=walls, start=Pose2(1.0, 3.0, 0.0),
                 ceilings=(Ceiling((0.0, 0.0), (10.0, 6.0), 2.5),), lamps=lamps,
                 pictures=pictures, objects=objects,
                 routes=(Route("through", ((1.0, 3.0), (9.0, 3.0))),))


def route_gap_m(world: World) -> float:
    """Least distance from the routes' legs to any object's footprint, m (independent of
    the world's own check)."""
    corners = world.object_corners()
    if len(corners) == 0:
        return math.inf
    a, b = corners.reshape(-1, 2), np.roll(corners, -1, axis=1).reshape(-1, 2)
    gaps = []
    for route in world.routes:
        for p, q in itertools.pairwise(np.asarray(route.waypoints, dtype=float)):
            samples = p + np.linspace(0.0, 1.0, 400)[:, None] * (q - p)
            gaps.append(point_segment_distances(samples, a, b).min())
    return min(gaps)


def changed(change: SceneChange, seed: int = 0, keep: np.ndarray | None = None):
    return change_world(office(), change, np.random.default_rng(seed), keep)


class TestLighting:
    def test_scale_multiplies_the_brightness(self) -> None:
        world = changed(SceneChange(lighting=LightingChange(scale=0.5))).world
        assert world.lighting.brightness == office().lighting.brightness * 0.5

    def test_a_scale_beyond_the_range_names_the_world(self) -> None:
        with pytest.raises(ValueError, match=r"brightness 330 of world 'office' leave"):
            changed(SceneChange(lighting=LightingChange(scale=3.0)))

    @pytest.mark.parametrize(("fraction", "count"), [(0.5, 3), (1.0, 6), (0.2, 1)])
    def test_lamps_off_switches_that_share_off(self, fraction: float, count: int) -> None:
        result = changed(SceneChange(lighting=LightingChange(lamps_off=fraction)))
        off = [i for i, lamp in enumerate(result.world.lamps) if not lamp.on]
        assert off == list(result.lamps_off) and len(off) == count
        assert [dataclasses.replace(lamp, on=True) for lamp in result.world.lamps] == list(
            office().lamps)

    def test_lamps_off_in_a_world_without_lamps_changes_nothing(self) -> None:
        dark = dataclasses.replace(office(), lamps=())
        result = change_world(dark, SceneChange(lighting=LightingChange(lamps_off=0.5)),
                              np.random.default_rng(0))
        assert result.world == dark and result.lamps_off == ()

    def test_another_hour_dims_the_daylight_and_turns_the_sun(self) -> None:
        taught = office()
        dusk = changed(SceneChange(lighting=LightingChange(hour=17.0))).world
        assert dusk.lighting.daylight == pytest.approx(
            taught.lighting.daylight * math.sin(math.pi * 11 / 12))
        assert dusk.sky.sun_azimuth_deg == pytest.approx(taught.sky.sun_azimuth_deg - 75.0)
        assert dusk.sky.horizon < taught.sky.horizon
        night = changed(SceneChange(lighting=LightingChange(hour=23.0))).world
        assert night.lighting.daylight == 0.0 and night.sky.zenith > 0.0

    def test_daylight_peaks_at_the_teach_hour_and_is_zero_at_night(self) -> None:
        assert daylight_at(TEACH_HOUR) == 1.0
        assert daylight_at(2.0) == daylight_at(22.0) == 0.0
        assert daylight_at(6.0) == pytest.approx(0.0) and daylight_at(18.0) == pytest.approx(0.0)
        assert daylight_at(9.0) == pytest.approx(daylight_at(15.0)) == pytest.approx(
            math.sqrt(0.5))

    def test_the_step_applies_from_its_time_on(self) -> None:
        light = LightingChange(step_factor=0.4, step_at_s=2.5)
        assert light.gain_at(0) == light.gain_at(2_499_999_999) == 1.0
        assert light.gain_at(2_500_000_000) == light.gain_at(10**12) == 0.4
        assert light.has_step and not LightingChange().has_step

    @pytest.mark.parametrize(("fields", "message"), [
        ({"scale": 0.0}, "scale must be > 0"),
        ({"scale": math.nan}, "scale must be > 0"),
        ({"lamps_off": 1.2}, r"lamps-off must be in \[0, 1\]"),
        ({"hour": 25.0}, r"hour must be in \[0, 24\]"),
        ({"step_factor": -1.0}, "step factor must be > 0"),
        ({"step_at_s": -2.0}, "step time must be >= 0 s"),
    ])
    def test_values_are_checked(self, fields: dict[str, float], message: str) -> None:
        with pytest.raises(ValueError, match=message):
            LightingChange(**fields)

    def test_the_rendered_scene_follows_the_step(self) -> None:
        config = dataclasses.replace(SimConfig(), sensor=SensorConfig.ideal(),
                                     render=dataclasses.replace(SimConfig().render,
                                                                illumination_amplitude=0.0))
        before, after = self.frames_around_step(config, 0.5, after_s=(0.1,))
        lit = (before > 40) & (before < 200)
        assert np.median(after[0][lit] / before[lit]) == pytest.approx(0.5, abs=0.05)

    def test_auto_exposure_follows_the_step_late(self) -> None:
        config = dataclasses.replace(SimConfig(), render=dataclasses.replace(
            SimConfig().render, illumination_amplitude=0.0))
        tau = config.sensor.exposure_time_constant_s
        before, after = self.frames_around_step(config, 0.5, after_s=(0.07, 6 * tau))
        circle = before > 0
        first, settled = (float(np.mean(a[circle])) for a in after)
        assert first < 0.65 * np.mean(before[circle])  # the light fell: a dark frame
        assert settled == pytest.approx(np.mean(before[circle]), rel=0.1)  # exposure caught up

    @staticmethod
    def frames_around_step(config: SimConfig, factor: float, after_s: tuple[float, ...]
                           ) -> tuple[np.ndarray, list[np.ndarray]]:
        """The frame just before a light step at 2 s (auto-exposure settled) and frames
        ``after_s`` seconds after it, rendered every frame period from the start."""
        sim = Simulation(office(), config)
        step_ns = 2_000_000_000
        sim.light_gain_at = LightingChange(step_factor=factor, step_at_s=step_ns / 1e9).gain_at
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        wanted = [step_ns + round(s * 1e9) for s in after_s]
        before, after = None, []
        while len(after) < len(wanted):
            frame = renderer.render(sim)
            if frame.t_ns < step_ns:
                before = frame.image.astype(float)
            elif frame.t_ns >= wanted[len(after)]:
                after.append(frame.image.astype(float))
            sim.step_until(sim.now_ns + config.frame_period_ns)
        assert before is not None
        return before, after


class TestMovedObjects:
    def test_the_fraction_moves_within_the_bounds_and_the_rest_stays(self) -> None:
        taught = office()
        result = changed(SceneChange(moved_fraction=0.67), seed=3)
        assert len(result.moved) + len(result.stuck) == 2 and len(result.moved) >= 1
        for i, (old, new) in enumerate(zip(taught.objects, result.world.objects, strict=True)):
            if i in result.moved:
                assert old.movable and new != old
                assert new.size == old.size and new.height_m == old.height_m
                assert math.dist(new.center, old.center) <= MOVE_MAX_M
                assert abs(new.yaw_deg - old.yaw_deg) <= TURN_MAX_DEG
            else:
                assert new == old
        assert result.world.furniture == taught.furniture
        assert result.moved_from == tuple(taught.objects[i] for i in result.moved)
        for i, (before, now) in zip(result.moved, result.moved_footprints(), strict=True):
            assert np.array_equal(before, box_corners(*taught.objects[i].footprint()))
            assert np.array_equal(now, result.world.object_corners()[i])

    @pytest.mark.parametrize("seed", range(6))
    def test_the_route_stays_clear_and_the_world_valid(self, seed: int) -> None:
        result = changed(SceneChange(moved_fraction=1.0), seed=seed)
        assert result.moved and set(result.moved) | set(result.stuck) == {0, 1, 2}
        assert route_gap_m(result.world) >= CLEARANCE_M
        world = result.world
        assert World(**{f.name: getattr(world, f.name) for f in dataclasses.fields(World)})

    @pytest.mark.parametrize("seed", range(4))
    def test_moved_objects_stay_inside_and_apart(self, seed: int) -> None:
        world = changed(SceneChange(moved_fraction=1.0), seed=seed).world
        corners = world.object_corners()
        assert (corners > 0.05).all() and (corners[..., 0] < 9.95).all()
        assert (corners[..., 1] < 5.95).all()
        sim = Simulation(world, SimConfig())
        assert sim.free_space.is_reachable(np.array([[9.0, 3.0]])).all()

    def test_the_landmarks_stay_where_they_were_taught(self) -> None:
        taught = office()
        # The bin pushed against the west wall hides the patches behind it: a field drawn
        # for the changed world loses them, and every texture after them shifts.
        bin_at_wall = dataclasses.replace(taught.objects[0], center=(0.35, 4.0),
                                          size=(1.6, 0.5), yaw_deg=90.0)
        moved = dataclasses.replace(taught, objects=(bin_at_wall, *taught.objects[1:]))
        original = Simulation(taught, SimConfig()).landmarks
        fresh = Simulation(moved, SimConfig()).landmarks
        kept = Simulation(moved, SimConfig(), landmark_world=taught).landmarks
        assert len(fresh) < len(original)
        assert np.array_equal(kept.positions_w, original.positions_w)
        assert np.array_equal(kept.textures, original.textures)

    def test_points_kept_clear_stay_clear(self) -> None:
        keep = np.array([[1.5, 2.0], [4.0, 3.6]])
        for seed in range(5):
            result = changed(SceneChange(moved_fraction=1.0), seed=seed, keep=keep)
            for i in result.moved:
                corners = box_corners(*result.world.objects[i].footprint())
                edges = point_segment_distances(keep, corners, np.roll(corners, -1, axis=0))
                assert edges.min() >= KEEP_CLEAR_M

    def test_an_object_with_no_place_stays_and_is_counted(self) -> None:
        everywhere = np.array([[x, y] for x in np.arange(0.0, 10.1, 0.5)
                               for y in np.arange(0.0, 6.1, 0.5)])
        result = changed(SceneChange(moved_fraction=1.0), keep=everywhere)
        assert result.moved == () and result.stuck == (0, 1, 2)
        assert result.world == office()

    def test_the_same_seed_gives_the_same_world(self) -> None:
        change = SceneChange(moved_fraction=0.5, removed_fraction=0.5,
                             lighting=LightingChange(lamps_off=0.5))
        assert changed(change, seed=7) == changed(change, seed=7)

    def test_a_world_without_movable_objects_stays(self) -> None:
        still = dataclasses.replace(office(), objects=office().objects[3:])
        result = change_world(still, SceneChange(moved_fraction=0.5), np.random.default_rng(0))
        assert result.world == still and result.moved == result.stuck == ()

    @pytest.mark.parametrize("fraction", [-0.1, 1.5, math.nan])
    def test_the_fraction_is_checked(self, fraction: float) -> None:
        with pytest.raises(ValueError, match=r"moved fraction must be in \[0, 1\]"):
            SceneChange(moved_fraction=fraction)


class TestDoorsAndRemovals:
    def test_a_door_turns_to_its_opening(self) -> None:
        world = changed(SceneChange(doors=(("door", 100.0),))).world
        assert world.objects[4].open_deg == 100.0
        assert world.objects[:4] == office().objects[:4]

    def test_a_door_closed_across_the_route_is_refused_naming_both(self) -> None:
        with pytest.raises(ValueError, match=r"door 'door' at 0 deg: route 'through' leg 0->1 "
                                             r"is 0.00 m from object 4"):
            changed(SceneChange(doors=(("door", 0.0),)))

    def test_an_unknown_door_lists_the_doors(self) -> None:
        with pytest.raises(ValueError, match=r"no door named 'gate' \(doors: door\)"):
            changed(SceneChange(doors=(("gate", 90.0),)))

    def test_named_pictures_and_objects_go(self) -> None:
        result = changed(SceneChange(removed=("rocket", "whiteboard")))
        assert [p.name for p in result.world.pictures] == ["", "", "exit"]
        assert [o.name for o in result.world.objects] == ["bin", "", "", "door"]
        assert result.removed_pictures == result.removed_objects == 1

    def test_an_unknown_name_lists_the_names(self) -> None:
        with pytest.raises(ValueError, match=r"no picture or object named 'clock' \(named: "
                                             r"bin, door, exit, rocket, whiteboard\)"):
            changed(SceneChange(removed=("clock",)))

    def test_a_fraction_of_the_movable_pictures_goes(self) -> None:
        result = changed(SceneChange(removed_fraction=0.67))
        assert result.removed_pictures == 2 and len(result.world.pictures) == 2
        assert result.world.pictures[-1].name == "exit"  # not movable: stays

    def test_a_fraction_of_no_movable_pictures_takes_nothing(self) -> None:
        bare = dataclasses.replace(office(), pictures=office().pictures[3:])
        result = change_world(bare, SceneChange(removed_fraction=0.5), np.random.default_rng(0))
        assert result.world == bare and result.removed_pictures == 0


def test_no_change_is_the_same_world() -> None:
    result = changed(SceneChange())
    assert result.world == office() and result.moved == result.stuck == result.lamps_off == ()
    assert SceneChange().is_none and not SceneChange(moved_fraction=0.1).is_none


@pytest.mark.parametrize("name", builtin_world_names())
def test_a_fifth_of_a_builtin_world_moves_and_its_routes_stay_clear(name: str) -> None:
    world = load_world(name)
    change = SceneChange(moved_fraction=0.2)
    movable = [o for o in world.objects if o.movable and o.kind != "door"]
    result = change_world(world, change, np.random.default_rng(1))
    assert len(result.moved) + len(result.stuck) == round(0.2 * len(movable))
    assert len(result.moved) >= len(result.stuck)
    assert route_gap_m(result.world) >= CLEARANCE_M
