from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import ShapeError
from shared.pose import Pose2
from sim._geometry import point_segment_distances, points_in_polygons
from sim.free_space import WALL_HALF_THICKNESS_M, FreeSpaceMap
from sim.landmarks import (
    PATCH_PX,
    PROUD_M,
    LandmarkField,
    Surface,
    _jittered_grid,
    generate_landmarks,
    make_textures,
)
from sim.world import Box, Ceiling, LandmarkDensity, Wall, World, load_world
from tests.sim.rooms import box_room

GAP_M = 0.03  # the documented least plain gap between neighbouring patches


def wall_face_coordinates(
    world: World, field: LandmarkField
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Wall patches as (wall index, face +1/-1, distance along the wall from its start, z)."""
    on_wall = field.surface == Surface.WALL
    xy = field.positions_w[on_wall, :2]
    a = np.array([w.start for w in world.walls])
    b = np.array([w.end for w in world.walls])
    wall = point_segment_distances(xy, a, b).argmin(axis=1)
    direction = (b - a)[wall] / np.linalg.norm(b - a, axis=1)[wall, None]
    along = np.einsum("ij,ij->i", xy - a[wall], direction)
    left = np.column_stack([-direction[:, 1], direction[:, 0]])
    face = np.sign(np.einsum("ij,ij->i", field.normals_w[on_wall, :2], left)).astype(int)
    return wall, face, along, field.positions_w[on_wall, 2]


def assert_no_overlap_on_walls(world: World, field: LandmarkField) -> None:
    """Square patches on one wall face keep >= GAP_M of plain wall between them."""
    wall, face, along, z = wall_face_coordinates(world, field)
    sizes = field.sizes_m[field.surface == Surface.WALL]
    for w, f in {(int(w), int(f)) for w, f in zip(wall, face, strict=True)}:
        on = (wall == w) & (face == f)
        if on.sum() < 2:
            continue
        size = sizes[on]
        assert np.all(size == size[0])  # one size per surface
        uz = np.column_stack([along[on], z[on]])
        chebyshev = np.abs(uz[:, None] - uz[None]).max(axis=-1) + np.eye(len(uz)) * 1e9
        assert chebyshev.min() >= size[0] + GAP_M - 1e-9


@pytest.fixture(scope="module")
def lab() -> World:
    """The lab's floor plan with the patch densities it had before it was textured."""
    return dataclasses.replace(load_world("lab"), landmarks=LandmarkDensity(8.0, 8.0, 3.0, 0.15))


@pytest.fixture(scope="module")
def lab_field(lab: World) -> LandmarkField:
    return generate_landmarks(lab, np.random.default_rng(3))


class TestPlacement:
    def test_same_seed_same_field_other_seed_other_field(
        self, lab: World, lab_field: LandmarkField
    ) -> None:
        again = generate_landmarks(lab, np.random.default_rng(3))
        for name in ("ids", "positions_w", "normals_w", "surface", "sizes_m", "textures"):
            assert np.array_equal(getattr(lab_field, name), getattr(again, name))
        other = generate_landmarks(lab, np.random.default_rng(4))
        assert len(other) != len(lab_field) or not np.array_equal(
            other.positions_w, lab_field.positions_w
        )

    def test_count_scales_with_density_scale(self, lab: World, lab_field: LandmarkField) -> None:
        double = generate_landmarks(lab, np.random.default_rng(3), density_scale=2.0)
        assert len(double) / len(lab_field) == pytest.approx(2.0, rel=0.1)
        assert len(generate_landmarks(lab, np.random.default_rng(3), density_scale=0.0)) == 0

    def test_count_matches_density_on_plain_walls(self) -> None:
        density = LandmarkDensity(wall_per_m2=2.0, furniture_per_m2=0.0, ceiling_per_m2=0.0)
        world = box_room((10.0, 8.0), density=density)
        field = generate_landmarks(world, np.random.default_rng(0))
        # Inner faces only; usable band: 0.25 m from each end, z from 0.3 to 2.5 - 0.075 - 0.03.
        usable = sum(w.length_m - 0.5 for w in world.walls) * (2.5 - 0.105 - 0.3)
        assert len(field) == pytest.approx(2.0 * usable, rel=0.08)
        assert set(field.surface.tolist()) == {Surface.WALL}
        # All on the inner faces: normals point towards the room's centre.
        to_centre = np.array([5.0, 4.0]) - field.positions_w[:, :2]
        assert np.all(np.einsum("ij,ij->i", field.normals_w[:, :2], to_centre) > 0)

    def test_surfaces_normals_and_heights(self, lab: World, lab_field: LandmarkField) -> None:
        f = lab_field
        assert f.ids.dtype == np.int64 and np.array_equal(f.ids, np.arange(len(f)))
        assert f.sizes_m.dtype == np.float64 and np.all(f.sizes_m == 0.15)  # the default
        assert f.surface.dtype == np.int8 and set(f.surface.tolist()) == {0, 1, 2}
        assert np.allclose(np.linalg.norm(f.normals_w, axis=1), 1.0)
        ceiling = f.surface == Surface.CEILING
        assert np.all(f.normals_w[ceiling] == [0.0, 0.0, -1.0])
        assert np.allclose(f.positions_w[ceiling, 2], 2.6 - PROUD_M)
        assert np.all(f.normals_w[~ceiling, 2] == 0.0)
        assert np.all(f.positions_w[f.surface == Surface.WALL, 2] >= 0.3)
        assert np.all(f.positions_w[~ceiling, 2] + 0.075 < 2.6)

    def test_wall_patches_sit_on_a_wall_face_away_from_its_ends(
        self, lab: World, lab_field: LandmarkField
    ) -> None:
        on_wall = lab_field.positions_w[lab_field.surface == Surface.WALL, :2]
        a = np.array([w.start for w in lab.walls])
        b = np.array([w.end for w in lab.walls])
        distances = point_segment_distances(on_wall, a, b)
        nearest = distances.argmin(axis=1)
        assert np.allclose(distances.min(axis=1), WALL_HALF_THICKNESS_M + PROUD_M)
        d = b[nearest] - a[nearest]
        t = np.einsum("ij,ij->i", on_wall - a[nearest], d) / np.einsum("ij,ij->i", d, d)
        along = t * np.linalg.norm(d, axis=1)
        assert np.all((along >= 0.25 - 1e-9) & (along <= np.linalg.norm(d, axis=1) - 0.25 + 1e-9))

    def test_normals_point_into_reachable_free_space(
        self, lab: World, lab_field: LandmarkField
    ) -> None:
        f = lab_field
        probe = f.positions_w + 0.05 * f.normals_w
        a = np.array([w.start for w in lab.walls])
        b = np.array([w.end for w in lab.walls])
        assert np.all(
            point_segment_distances(probe[:, :2], a, b).min(axis=1) > WALL_HALF_THICKNESS_M
        )
        inside = points_in_polygons(probe[:, :2], lab.furniture_corners())
        heights = np.array([box.height_m for box in lab.furniture])
        assert not np.any(inside & (probe[:, 2:3] < heights))
        reach = f.positions_w[:, :2] + 0.25 * f.normals_w[:, :2]
        assert FreeSpaceMap.from_world(lab).is_reachable(reach).all()

    def test_nothing_on_the_unreachable_side_of_the_campus_corridor(self) -> None:
        # The built-in campus carries no patches (its landmarks are its textures): ask for some.
        campus = dataclasses.replace(load_world("campus"),
                                     landmarks=LandmarkDensity(0.5, 0.8, 4.0, 0.7))
        f = generate_landmarks(campus, np.random.default_rng(0))
        x, y = f.positions_w[:, 0], f.positions_w[:, 1]
        assert not np.any((x < 19.9) & ((y < 8.4) | (y > 11.6)))
        facade = (f.positions_w[:, 2] > 3.0) & (f.surface == Surface.WALL)
        assert np.sum(facade) > 50  # facades carry patches high up
        assert_no_overlap_on_walls(campus, f)

    def test_lab_patches_do_not_overlap(self, lab: World, lab_field: LandmarkField) -> None:
        assert_no_overlap_on_walls(lab, lab_field)

    def test_each_element_has_its_own_patch_size_or_the_default(self) -> None:
        room = box_room((8.0, 6.0))
        walls = (Wall(room.walls[0].start, room.walls[0].end, 2.5, patch_size_m=0.6),)
        world = World(
            name="sizes",
            walls=walls + room.walls[1:],
            start=Pose2(2.0, 3.0),
            furniture=(
                Box((5.0, 3.0), (1.6, 0.8), 30.0, 1.0, patch_size_m=0.3),
                Box((6.5, 1.5), (0.8, 0.8), 0.0, 0.75),
            ),
            ceilings=(Ceiling((0.0, 0.0), (4.0, 6.0), 2.5, patch_size_m=0.25),
                      Ceiling((4.0, 0.0), (8.0, 6.0), 2.5)),
            landmarks=LandmarkDensity(
                wall_per_m2=2.0, furniture_per_m2=6.0, ceiling_per_m2=3.0, patch_size_m=0.2
            ),
        )
        f = generate_landmarks(world, np.random.default_rng(1))
        wall, _, along, z = wall_face_coordinates(world, f)
        on_wall = f.surface == Surface.WALL
        size = f.sizes_m[on_wall]
        assert np.all(size == np.where(wall == 0, 0.6, 0.2)) and np.sum(wall == 0) > 10
        # Whole patches on their wall, clear of the walls they abut (centre lines at the ends).
        length = np.array([w.length_m for w in world.walls])[wall]
        margin = WALL_HALF_THICKNESS_M + size / 2
        assert np.all((along >= margin) & (along <= length - margin))
        assert np.all((z - size / 2 >= GAP_M - 1e-9) & (z + size / 2 <= 2.5 - GAP_M + 1e-9))
        assert_no_overlap_on_walls(world, f)

        on_box = f.surface == Surface.FURNITURE
        big_box = points_in_polygons(
            f.positions_w[on_box, :2] - 0.01 * f.normals_w[on_box, :2],
            world.furniture_corners()[:1],
        )[:, 0]
        assert big_box.sum() > 5 and (~big_box).sum() > 2
        assert np.all(f.sizes_m[on_box] == np.where(big_box, 0.3, 0.2))
        top = f.positions_w[on_box, 2] + f.sizes_m[on_box] / 2
        assert np.all(top <= np.where(big_box, 1.0, 0.75) - GAP_M + 1e-9)

        on_ceiling = f.surface == Surface.CEILING
        west = f.positions_w[on_ceiling, 0] < 4.0
        assert west.sum() > 10 and (~west).sum() > 10
        assert np.all(f.sizes_m[on_ceiling] == np.where(west, 0.25, 0.2))

    def test_dense_big_patches_saturate_without_overlapping(self) -> None:
        density = LandmarkDensity(
            wall_per_m2=50.0, furniture_per_m2=0.0, ceiling_per_m2=0.0, patch_size_m=0.5
        )
        world = box_room((10.0, 8.0), density=density)
        field = generate_landmarks(world, np.random.default_rng(2))
        assert_no_overlap_on_walls(world, field)
        # At most one patch per 0.53 m square of the usable band (ends: 0.25 m + half
        # thickness past the corner's centre line; z from 0.3 to 2.5 - 0.28).
        usable = sum(w.length_m - 0.6 for w in world.walls) * (2.5 - 0.28 - 0.3)
        assert usable / 0.53**2 * 0.85 <= len(field) <= usable / 0.53**2 * 1.15

    def test_arrays_are_read_only_and_shapes_checked(self, lab_field: LandmarkField) -> None:
        with pytest.raises(ValueError, match="read-only"):
            lab_field.positions_w[0, 0] = 1.0
        n = 3
        with pytest.raises(
            ShapeError, match=r"textures: expected shape \(3, 16, 16\), got \(3, 8, 8\)"
        ):
            LandmarkField(
                np.arange(n),
                np.zeros((n, 3)),
                np.zeros((n, 3)),
                np.zeros(n, np.int8),
                np.full(n, 0.15),
                np.zeros((n, 8, 8), np.uint8),
            )
        with pytest.raises(ShapeError, match=r"sizes_m: expected shape \(3,?\), got \(2,\)"):
            LandmarkField(
                np.arange(n),
                np.zeros((n, 3)),
                np.zeros((n, 3)),
                np.zeros(n, np.int8),
                np.full(2, 0.15),
                np.zeros((n, 16, 16), np.uint8),
            )

    def test_bad_arguments(self, lab: World) -> None:
        with pytest.raises(ValueError, match="density_scale"):
            generate_landmarks(lab, np.random.default_rng(0), density_scale=-1.0)

    @settings(max_examples=50, deadline=None)
    @given(
        width=st.floats(0.1, 20.0),
        height=st.floats(0.1, 5.0),
        density=st.floats(0.1, 10.0),
        pitch=st.floats(0.01, 1.0),
        seed=st.integers(0, 2**32 - 1),
    )
    def test_jittered_grid_stays_inside_and_keeps_its_pitch(
        self, width: float, height: float, density: float, pitch: float, seed: int
    ) -> None:
        points = _jittered_grid(np.random.default_rng(seed), width, height, density, pitch)
        assert np.all((points >= 0) & (points <= [width, height]))
        # At most one point per cell; cells are >= pitch and >= 1 / sqrt(density) wide.
        cell = max(pitch, 1 / math.sqrt(density))
        assert len(points) <= (math.ceil(width / cell) + 1) * (math.ceil(height / cell) + 1)
        if len(points) > 1:
            chebyshev = (
                np.abs(points[:, None] - points[None]).max(axis=-1) + np.eye(len(points)) * 1e9
            )
            assert chebyshev.min() >= max(pitch, 0.2 / math.sqrt(density)) - 1e-9

    @settings(max_examples=15, deadline=None)
    @given(
        size=st.floats(0.05, 1.0),
        density=st.floats(0.2, 40.0),
        seed=st.integers(0, 2**32 - 1),
    )
    def test_patches_never_overlap_on_a_wall(self, size: float, density: float, seed: int) -> None:
        world = box_room(
            (6.0, 4.0),
            density=LandmarkDensity(
                wall_per_m2=density, furniture_per_m2=0.0, ceiling_per_m2=0.0, patch_size_m=size
            ),
        )
        field = generate_landmarks(world, np.random.default_rng(seed))
        assert np.all(field.sizes_m == size)
        assert_no_overlap_on_walls(world, field)


def harris_peak_offset(texture: np.ndarray, scale: float) -> float:
    """Distance (texture pixels) of the Harris maximum from the centre of a patch in mid-grey."""
    size = round(PATCH_PX * scale)
    patch = (
        texture
        if size == PATCH_PX
        else cv2.resize(texture, (size, size), interpolation=cv2.INTER_LINEAR)
    )
    image = np.full((size + 32, size + 32), 128, np.float32)
    image[16 : 16 + size, 16 : 16 + size] = patch
    response = cv2.cornerHarris(image, 3, 3, 0.04)
    row, col = np.unravel_index(np.argmax(response), response.shape)
    centre = 16 + (size - 1) / 2
    return math.hypot(row - centre, col - centre) / scale


def zncc(a: np.ndarray, b: np.ndarray) -> float:
    a = a.astype(float) - a.mean()
    b = b.astype(float) - b.mean()
    return float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum()))


class TestTextures:
    @pytest.fixture(scope="class")
    @classmethod
    def textures(cls) -> np.ndarray:
        return make_textures(np.random.default_rng(11), 200)

    @pytest.mark.parametrize("scale", [1.0, 1.5, 2.0, 4.0])
    def test_one_dominant_harris_corner_at_the_centre(
        self, textures: np.ndarray, scale: float
    ) -> None:
        offsets = [harris_peak_offset(t, scale) for t in textures]
        assert max(offsets) <= 1.5

    def test_harris_corner_at_the_centre_when_small(self, textures: np.ndarray) -> None:
        # 12 px: the patch 2.5 m away on the default lens.
        offsets = np.array([harris_peak_offset(t, 0.75) for t in textures])
        assert np.mean(offsets <= 1.5) >= 0.99

    def test_border_fades_to_the_surface_level(self, textures: np.ndarray) -> None:
        ring = np.concatenate(
            [textures[:, 0], textures[:, -1], textures[:, :, 0], textures[:, :, -1]], axis=1
        )
        assert np.abs(ring.astype(int) - 128).max() <= 2
        assert np.abs(textures.reshape(len(textures), -1).mean(axis=1) - 128).max() < 40

    def test_zncc_tells_patches_apart(self, textures: np.ndarray) -> None:
        windows = textures[:, 2:13, 2:13]  # 11 x 11 around the centre
        assert zncc(windows[0], windows[0]) == pytest.approx(1.0)
        scores = np.array(
            [zncc(windows[i], windows[j]) for i in range(80) for j in range(i + 1, 80)]
        )
        assert np.median(scores) < 0.2
        assert np.mean(np.abs(scores)) < 0.6
        assert np.percentile(scores, 90) < 0.9

    def test_deterministic(self) -> None:
        assert np.array_equal(
            make_textures(np.random.default_rng(5), 20), make_textures(np.random.default_rng(5), 20)
        )
