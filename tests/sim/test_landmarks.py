from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import ShapeError
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
from sim.world import LandmarkDensity, World, load_world
from tests.sim.rooms import box_room


@pytest.fixture(scope="module")
def lab() -> World:
    return load_world("lab")


@pytest.fixture(scope="module")
def lab_field(lab: World) -> LandmarkField:
    return generate_landmarks(lab, np.random.default_rng(3))


class TestPlacement:
    def test_same_seed_same_field_other_seed_other_field(
        self, lab: World, lab_field: LandmarkField
    ) -> None:
        again = generate_landmarks(lab, np.random.default_rng(3))
        for name in ("ids", "positions_w", "normals_w", "surface", "textures"):
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
        campus = load_world("campus")
        f = generate_landmarks(campus, np.random.default_rng(0))
        x, y = f.positions_w[:, 0], f.positions_w[:, 1]
        assert not np.any((x < 19.9) & ((y < 8.4) | (y > 11.6)))
        assert np.sum(f.positions_w[:, 2] > 3.0) > 50  # facades carry patches high up

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
                np.zeros((n, 8, 8), np.uint8),
            )

    def test_bad_arguments(self, lab: World) -> None:
        with pytest.raises(ValueError, match="density_scale"):
            generate_landmarks(lab, np.random.default_rng(0), density_scale=-1.0)

    @settings(max_examples=50, deadline=None)
    @given(
        width=st.floats(0.1, 20.0),
        height=st.floats(0.1, 5.0),
        density=st.floats(0.1, 10.0),
        seed=st.integers(0, 2**32 - 1),
    )
    def test_jittered_grid_stays_inside_and_does_not_clump(
        self, width: float, height: float, density: float, seed: int
    ) -> None:
        points = _jittered_grid(np.random.default_rng(seed), width, height, density)
        assert np.all((points >= 0) & (points <= [width, height]))
        if len(points) > 1:
            gaps = (
                np.linalg.norm(points[:, None] - points[None], axis=-1) + np.eye(len(points)) * 1e9
            )
            assert gaps.min() >= 0.2 / math.sqrt(density) - 1e-9


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
