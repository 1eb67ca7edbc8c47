from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from shared.camera_model import CameraModel
from shared.camera_mount import camera_pose_world, rotation_base_cam
from shared.config import CameraMountConfig
from shared.errors import ShapeError
from shared.pose import Pose2
from sim._geometry import point_segment_distances, points_in_polygons
from sim.config import RenderConfig, SensorConfig, SimConfig
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.surfaces import SurfaceShader
from sim.world import Box, Ceiling, Wall, World, load_world

CAMERA = CameraModel.default()
H_CAM = 0.3
WALL_H = 2.5
ROOM = (10.0, 6.0)
COLUMN = 400  # the image's centre column (cx = 399.5)
LAB = load_world("lab")


def room(*, ceiling: bool = True, furniture: tuple[Box, ...] = ()) -> World:
    """A 10 x 6 m room, walls 2.5 m high, optionally roofed at the walls' height."""
    w, h = ROOM
    corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
    walls = tuple(
        Wall(a, b, WALL_H) for a, b in zip(corners, corners[1:] + corners[:1], strict=True)
    )
    ceilings = (Ceiling((0.0, 0.0), ROOM, WALL_H),) if ceiling else ()
    return World(
        name="room", walls=walls, start=Pose2(1.0, 1.0), furniture=furniture, ceilings=ceilings
    )


def exact_shader(world: World, mount: CameraMountConfig | None = None) -> SurfaceShader:
    """One cell per pixel, no blur: every pixel is shaded by its own ray."""
    mount = mount or CameraMountConfig(height_m=H_CAM)
    return SurfaceShader(
        world, CAMERA, rotation_base_cam(mount), mount.height_m, downsample=1, blur_sigma_cells=0.0
    )


def column_elevations_deg() -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Rows of the centre column that look forward, and their rays' elevations (level camera)."""
    rows = np.arange(CAMERA.height)
    bearings, valid = CAMERA.lift(np.column_stack([np.full(rows.shape, COLUMN), rows]))
    base = bearings @ rotation_base_cam(CameraMountConfig()).T
    forward = valid & (base[:, 0] > 0)
    elevation = np.degrees(np.arctan2(base[:, 2], np.hypot(base[:, 0], base[:, 1])))
    return rows[forward], elevation[forward]


def band(image: npt.NDArray[np.uint8], lo_deg: float, hi_deg: float) -> npt.NDArray[np.uint8]:
    """Greys of the centre column's pixels with elevations in (lo, hi), clear of the ends."""
    rows, elevation = column_elevations_deg()
    inside = (elevation > lo_deg + 0.05) & (elevation < hi_deg - 0.05)
    assert inside.sum() >= 3, (lo_deg, hi_deg)
    return image[rows[inside], COLUMN]


def el(height_above_camera_m: float, distance_m: float) -> float:
    return math.degrees(math.atan2(height_above_camera_m, distance_m))


def facing_wall(distance_m: float) -> tuple[float, float]:
    """Camera position facing +x with the east wall's face ``distance_m`` ahead."""
    return (ROOM[0] - WALL_HALF_THICKNESS_M - distance_m, 3.0)


class TestKnownAnswers:
    @pytest.mark.parametrize(
        ("xy", "yaw_deg", "distance_m"),
        [
            (facing_wall(2.0), 0.0, 2.0),  # the brief's case: a wall 2 m ahead
            ((5.0, 4.45), 90.0, 1.5),  # north wall's face at y = 5.95
            ((3.05, 3.0), 180.0, 3.0),  # west wall's face at x = 0.05
            ((5.0, 2.55), -90.0, 2.5),  # south wall's face at y = 0.05
        ],
    )
    def test_facing_a_wall(
        self, xy: tuple[float, float], yaw_deg: float, distance_m: float
    ) -> None:
        image = exact_shader(room()).shade(xy, math.radians(yaw_deg))
        lo, hi = el(-H_CAM, distance_m), el(WALL_H - H_CAM, distance_m)
        wall = band(image, lo, hi)
        floor = band(image, -89.0, lo)
        ceiling = band(image, hi, 89.0)
        assert wall.max() - wall.min() <= 1  # one distance, one incidence
        assert floor.max() < wall.min()
        assert ceiling.min() > wall.max()
        # The boundaries are where the geometry puts them: just outside the band, no wall.
        assert band(image, lo - 1.5, lo).max() < wall.min()
        assert band(image, hi, hi + 1.5).min() > wall.max()

    def test_a_ray_passes_over_a_desk_to_the_wall_behind(self) -> None:
        desk_h, desk_d, wall_d = 0.75, 1.0, 3.0
        x, y = facing_wall(wall_d)
        desk = Box((x + desk_d + 0.3, y), (0.6, 1.6), 0.0, desk_h)  # front face desk_d ahead
        image = exact_shader(room(furniture=(desk,))).shade((x, y), 0.0)
        foot, top = el(-H_CAM, desk_d), el(desk_h - H_CAM, desk_d)
        front = band(image, foot, top)
        # Over the desk's top edge the ray meets the wall, up to the wall's top.
        wall = band(image, top, el(WALL_H - H_CAM, wall_d))
        assert front.max() - front.min() <= 1 and wall.max() - wall.min() <= 1
        assert abs(int(front[0]) - int(wall[0])) > 5
        floor = band(image, foot - 2.0, foot)  # at the desk's foot
        assert np.abs(floor.astype(int) - int(front[0])).min() > 5
        assert band(image, el(WALL_H - H_CAM, wall_d), 89.0).min() > wall.max()  # ceiling

    def test_mount_yaw_and_robot_yaw_agree(self) -> None:
        world = room()
        turned_mount = exact_shader(world, CameraMountConfig(height_m=H_CAM, yaw_deg=90.0))
        turned_robot = exact_shader(world)
        xy = (5.0, 3.0)
        a = turned_mount.shade(xy, 0.0).astype(int)
        b = turned_robot.shade(xy, math.pi / 2).astype(int)
        # Bins sit at fixed azimuths from the heading, so a pixel can change bin: compare broadly.
        assert np.mean(np.abs(a - b) <= 2) > 0.99

    def test_open_sky_and_ceilings_in_the_campus(self) -> None:
        world = load_world("campus")
        mount = CameraMountConfig()
        shader = SurfaceShader(world, CAMERA, rotation_base_cam(mount), mount.height_m)
        zenith = (40, 400)  # near the top of the image circle, looking up
        courtyard = shader.shade((26.0, 10.0), 0.0)
        corridor = shader.shade((10.0, 10.0), 0.0)
        sky = courtyard[zenith]
        assert sky >= courtyard.max() - 2  # the sky is the brightest surface
        assert corridor[zenith] < sky - 20  # under the corridor's roof: ceiling
        assert corridor[zenith] > corridor[560, 400]  # ceiling brighter than floor


class TestImage:
    def test_shape_mask_and_determinism(self) -> None:
        world = load_world("lab")
        mount = CameraMountConfig()
        shaders = [
            SurfaceShader(world, CAMERA, rotation_base_cam(mount), mount.height_m) for _ in range(2)
        ]
        a, b = (shader.shade((8.2, 10.0), 0.3) for shader in shaders)
        assert a.shape == (CAMERA.height, CAMERA.width) and a.dtype == np.uint8
        assert np.array_equal(a, b)
        assert a[0, 0] == a[0, -1] == a[-1, 0] == a[-1, -1] == 0
        assert a[300, 400] > 0

    def test_edges_make_weak_corners_next_to_landmarks(self) -> None:
        # Harris responses of the shaded surfaces alone stay far below those of the landmark
        # patches' corners, so the detector keeps finding landmarks.
        config = dataclasses.replace(SimConfig(), render=RenderConfig(illumination_amplitude=0.0),
                                     sensor=SensorConfig.ideal())
        sim = Simulation(load_world("lab"), config)
        pose = Pose2(8.0, 10.0, 0.0)
        sim.place_robot(pose)
        renderer = FisheyeRenderer.for_simulation(sim, CAMERA)
        frame = renderer.render(sim)
        T = camera_pose_world(frame.pose_w, config.camera_mount)
        shader = SurfaceShader(sim.world, CAMERA, rotation_base_cam(config.camera_mount), T[2, 3])
        background = shader.shade(T[:2, 3], frame.pose_w[2])

        def harris(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.float32]:
            return cv2.cornerHarris(image.astype(np.float32), 3, 3, 0.04)

        circle = cv2.erode((background > 0).astype(np.uint8), np.ones((15, 15), np.uint8)) > 0
        surfaces_max = harris(background)[circle].max()
        near = np.round(frame.visible_pixels_xy[frame.visible_distances_m < 3.0]).astype(int)
        assert near.shape[0] > 30
        peaks = cv2.dilate(harris(frame.image), np.ones((5, 5), np.uint8))[near[:, 1], near[:, 0]]
        assert surfaces_max < 0.01 * np.median(peaks)


class TestBadInput:
    def test_rotation_shape(self) -> None:
        with pytest.raises(ShapeError):
            SurfaceShader(room(), CAMERA, np.eye(2), H_CAM)

    @pytest.mark.parametrize(
        ("name", "value"),
        [
            ("downsample", 0),
            ("azimuth_bins", 4),
            ("blur_sigma_cells", -1.0),
            ("blur_sigma_cells", math.nan),
        ],
    )
    def test_out_of_range(self, name: str, value: float) -> None:
        with pytest.raises(ValueError, match=name):
            SurfaceShader(room(), CAMERA, np.eye(3), H_CAM, **{name: value})

    def test_camera_height(self) -> None:
        with pytest.raises(ValueError, match="camera_height_m"):
            SurfaceShader(room(), CAMERA, np.eye(3), 0.0)


def lab_segments() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Starts and ends (S, 2) of the lab's walls, then of its furniture's edges."""
    corners = LAB.furniture_corners()
    a = np.concatenate([np.array([w.start for w in LAB.walls]), corners.reshape(-1, 2)])
    b = np.concatenate(
        [np.array([w.end for w in LAB.walls]), np.roll(corners, -1, axis=1).reshape(-1, 2)]
    )
    return a, b


def brute_force_hits(
    xy: tuple[float, float], yaw: float, bins: int
) -> list[list[tuple[float, float, float, bool]]]:
    """Per bin ray in the lab: the visible hits near to far, as (centre-line distance,
    top height, cos of incidence, is a wall).

    Every wall and furniture edge is intersected with every ray (no culling, no bin
    ranges), and a hit is visible when its top is seen higher than every nearer hit's.
    """
    a, b = lab_segments()
    heights = [w.height_m for w in LAB.walls] + [f.height_m for f in LAB.furniture for _ in "abcd"]
    az = yaw - math.pi + (np.arange(bins) + 0.5) * 2 * math.pi / bins
    r = np.column_stack([np.cos(az), np.sin(az)])[:, None, :]  # (B, 1, 2)
    e, rel = (b - a)[None], (a - np.asarray(xy))[None]  # (1, S, 2)
    denom = r[..., 0] * e[..., 1] - r[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        d = (rel[..., 0] * e[..., 1] - rel[..., 1] * e[..., 0]) / denom
        s = (rel[..., 0] * r[..., 1] - rel[..., 1] * r[..., 0]) / denom
    cos_i = np.abs(denom) / np.hypot(e[..., 0], e[..., 1])
    out = []
    for k in range(bins):
        hit = np.flatnonzero((d[k] > 0) & (s[k] >= 0) & (s[k] <= 1))
        visible, best = [], -math.inf
        for i in hit[np.argsort(d[k, hit])]:
            if (heights[i] - H_CAM) / d[k, i] > best:
                best = (heights[i] - H_CAM) / d[k, i]
                visible.append((d[k, i], heights[i], cos_i[k, i], i < len(LAB.walls)))
        out.append(visible[:3])
    return out


class TestRayCast:
    @settings(max_examples=40, deadline=None)
    @given(x=st.floats(1.0, 29.0), y=st.floats(1.0, 19.0), yaw=st.floats(-math.pi, math.pi))
    def test_matches_brute_force(self, x: float, y: float, yaw: float) -> None:
        point = np.array([[x, y]])
        assume(point_segment_distances(point, *lab_segments()).min() > 0.2)
        assume(not points_in_polygons(point, LAB.furniture_corners()).any())
        bins = 90
        shader = SurfaceShader(LAB, CAMERA, np.eye(3), H_CAM, downsample=8, azimuth_bins=bins)
        c, s = math.cos(yaw), math.sin(yaw)
        rays = shader._bin_dirs @ np.array([[c, s], [-s, c]])  # private: the core under test
        env = shader._cast(point[0], yaw, rays)
        inv_dist = env.inv_dist.reshape(bins, -1)
        top = env.top.reshape(bins, -1)
        for k, hits in enumerate(brute_force_hits((x, y), yaw, bins)):
            assert np.count_nonzero(inv_dist[k] > 0) == len(hits), k
            for level, (d, height, cos_i, wall) in enumerate(hits):
                face = d - (WALL_HALF_THICKNESS_M / max(cos_i, 0.05) if wall else 0.0)
                assert 1.0 / inv_dist[k, level] == pytest.approx(max(face, 1e-3), rel=1e-4)
                rise = (height - H_CAM) * inv_dist[k, level]
                assert top[k, level] == pytest.approx(rise, rel=1e-5)
