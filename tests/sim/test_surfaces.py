"""The compiled surfaces (sim/surfaces.py) and the ray kernel that traces them (sim/_raycast.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt
import pytest

from shared.camera_model import CameraModel
from shared.camera_mount import camera_pose_world
from shared.config import CameraMountConfig
from shared.pose import Pose2
from sim.config import RenderConfig, SensorConfig, SimConfig
from sim.decor import Lamp, Picture, PlacedObject, Tree
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.surfaces import PICTURE_PROUD_M, Scene
from sim.world import Box, Ceiling, LandmarkDensity, Wall, World, load_world

CAMERA = CameraModel.default()
NO_PATCHES = LandmarkDensity(0.0, 0.0, 0.0)
QUIET = RenderConfig(illumination_amplitude=0.0)


def room(**decor: object) -> World:
    """A 10 x 6 m room, walls 2.5 m high, roofed, with ``decor`` (World fields)."""
    corners = [(0.0, 0.0), (10.0, 0.0), (10.0, 6.0), (0.0, 6.0)]
    walls = tuple(Wall(a, b, 2.5) for a, b in zip(corners, corners[1:] + corners[:1], strict=True))
    return World(name="room", walls=walls, start=Pose2(1.0, 3.0),
                 ceilings=(Ceiling((0.0, 0.0), (10.0, 6.0), 2.5),), landmarks=NO_PATCHES,
                 **decor)  # type: ignore[arg-type]


def renderer_for(world: World, pose: Pose2) -> tuple[Simulation, FisheyeRenderer]:
    sim = Simulation(world, dataclasses.replace(SimConfig(), render=QUIET,
                                                sensor=SensorConfig.ideal()))
    sim.place_robot(pose)
    return sim, FisheyeRenderer.for_simulation(sim, CAMERA)


def brute_force_depth(scene: Scene, o: npt.NDArray[np.float64],
                      rays: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Nearest hit along each ray (N, 3) over every primitive, the floor and the ceilings."""
    n = rays.shape[0]
    best = np.full(n, np.inf)
    rx, ry, rz = rays.T
    with np.errstate(divide="ignore", invalid="ignore"):
        for a, d, length, nrm, (z0, z1) in zip(scene.quad_a, scene.quad_d, scene.quad_len,
                                               scene.quad_n, scene.quad_z, strict=True):
            if (o[0] - a[0]) * nrm[0] + (o[1] - a[1]) * nrm[1] <= 0:
                continue
            den = rx * d[1] - ry * d[0]
            px, py = a[0] - o[0], a[1] - o[1]
            t = (px * d[1] - py * d[0]) / den
            s = (px * ry - py * rx) / den
            z = o[2] + t * rz
            ok = (t > 1e-4) & (s >= 0) & (s <= length) & (z >= z0) & (z <= z1)
            best = np.where(ok & (t < best), t, best)
        for c, ax, half, zf, up in zip(scene.flat_c, scene.flat_ax, scene.flat_half, scene.flat_z,
                                       scene.flat_up, strict=True):
            if (o[2] - zf) * up <= 0:
                continue
            t = (zf - o[2]) / rz
            lx, ly = o[0] + t * rx - c[0], o[1] + t * ry - c[1]
            ok = ((t > 1e-4) & (np.abs(lx * ax[0] + ly * ax[1]) <= half[0])
                  & (np.abs(-lx * ax[1] + ly * ax[0]) <= half[1]))
            best = np.where(ok & (t < best), t, best)
        for c, r, (z0, z1) in zip(scene.cyl_c, scene.cyl_r, scene.cyl_z, strict=True):
            qx, qy = o[0] - c[0], o[1] - c[1]
            a2 = rx**2 + ry**2
            b2 = qx * rx + qy * ry
            disc = b2**2 - a2 * (qx**2 + qy**2 - r**2)
            t = (-b2 - np.sqrt(disc)) / a2
            z = o[2] + t * rz
            ok = (disc >= 0) & (t > 1e-4) & (z >= z0) & (z <= z1)
            best = np.where(ok & (t < best), t, best)
        for c, r in zip(scene.sph_c, scene.sph_r, strict=True):
            q = o - c
            b2 = rays @ q
            disc = b2**2 - (q @ q - r**2)
            t = -b2 - np.sqrt(disc)
            ok = (disc >= 0) & (t > 1e-4)
            best = np.where(ok & (t < best), t, best)
        floor = np.where(rz < 0, -o[2] / rz, np.inf)
        best = np.minimum(best, floor)
        for lo, hi, zc in zip(scene.ceil_lo, scene.ceil_hi, scene.ceil_z, strict=True):
            t = (zc - o[2]) / rz
            x, y = o[0] + t * rx, o[1] + t * ry
            ok = (rz > 0) & (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])
            best = np.where(ok & (t < best), t, best)
    return best


class TestBuildScene:
    def test_walls_are_slabs_with_faces_pointing_out(self) -> None:
        _, renderer = renderer_for(room(), Pose2(1.0, 3.0))
        scene = renderer.scene
        assert scene.quad_a.shape == (16, 2)  # 4 walls x (2 faces + 2 end caps)
        # The south wall's inner face (its left) points north, 5 cm north of its line.
        north = np.flatnonzero((scene.quad_n[:, 1] > 0.99) & (np.abs(scene.quad_a[:, 1]) < 0.1))
        assert north.size == 1
        assert scene.quad_a[north[0], 1] == pytest.approx(WALL_HALF_THICKNESS_M)
        np.testing.assert_allclose(np.linalg.norm(scene.quad_d, axis=1), 1.0)
        # The viewer's right (d) is the normal turned clockwise... seen from the front.
        np.testing.assert_allclose(scene.quad_n[:, 0], scene.quad_d[:, 1])
        np.testing.assert_allclose(scene.quad_n[:, 1], -scene.quad_d[:, 0])

    def test_pictures_stand_proud_and_report_their_corners(self) -> None:
        world = room(pictures=(Picture((5.0, 5.8), "poster_rocket", 1.5),))
        _, renderer = renderer_for(world, Pose2(1.0, 3.0))
        scene = renderer.scene
        corners = scene.picture_corners_w[0]
        y = 6.0 - WALL_HALF_THICKNESS_M - PICTURE_PROUD_M
        np.testing.assert_allclose(corners[:, 1], y)
        # Facing the poster (looking north), its top-left corner is on the viewer's left (west).
        np.testing.assert_allclose(corners[0], [4.7, y, 1.8])
        np.testing.assert_allclose(corners[2], [5.3, y, 1.2])
        np.testing.assert_allclose(scene.picture_normals_w[0], [0.0, -1.0, 0.0])

    def test_boxes_have_tops_and_raised_ones_bottoms(self) -> None:
        world = room(furniture=(Box((5.0, 1.0), (1.6, 0.8), 0.0, 0.75, kind="desk"),),
                     objects=(PlacedObject("board", (5.0, 4.0), (1.2, 0.05), 1.0,
                                           elevation_m=0.7),))
        _, renderer = renderer_for(world, Pose2(1.0, 3.0))
        np.testing.assert_allclose(sorted(renderer.scene.flat_z), [0.7, 0.75, 1.7])


class TestTrace:
    @pytest.mark.parametrize(("name", "poses"), [
        ("lab", [(8.0, 10.0, 0.0), (15.0, 6.0, 100.0), (26.6, 13.0, 45.0), (19.6, 12.0, -80.0)]),
        ("campus", [(1.5, 10.0, 0.0), (30.0, 10.0, 200.0), (25.0, 4.0, 60.0)]),
    ])
    def test_depth_is_the_nearest_hit_of_every_ray(
        self, name: str, poses: list[tuple[float, float, float]]
    ) -> None:
        world = load_world(name)
        sim, renderer = renderer_for(world, Pose2(*poses[0][:2], math.radians(poses[0][2])))
        rng = np.random.default_rng(7)
        pick = rng.choice(renderer._pixels.shape[0], 4000, replace=False)
        for x, y, yaw_deg in poses:
            yaw = math.radians(yaw_deg)
            T = camera_pose_world((x, y, yaw), sim.config.camera_mount)
            _, depth = renderer.trace(T, yaw)
            rays = renderer._rays_c[pick] @ T[:3, :3].T
            expected = brute_force_depth(renderer.scene, T[:3, 3], rays)
            got = depth.ravel()[renderer._pixels[pick]]
            np.testing.assert_allclose(got, expected, rtol=1e-5)

    def test_facing_a_wall_at_a_known_distance(self) -> None:
        _, renderer = renderer_for(room(), Pose2(1.0, 3.0))
        T = camera_pose_world((1.0, 3.0, 0.0), CameraMountConfig())
        _, depth = renderer.trace(T, 0.0)
        # Optical centre 0.2 m ahead of the body's centre; the east wall's face at 9.95 m.
        assert depth[300, 400] == pytest.approx(9.95 - 1.2, abs=2e-3)

    def test_trees_and_open_sky(self) -> None:
        corners = [(0.0, 0.0), (20.0, 0.0), (20.0, 20.0), (0.0, 20.0)]
        walls = tuple(Wall(a, b, 3.0, texture="facade_brick")
                      for a, b in zip(corners, corners[1:] + corners[:1], strict=True))
        world = World(name="yard", walls=walls, start=Pose2(5.0, 10.0), landmarks=NO_PATCHES,
                      trees=(Tree((9.0, 10.0)),))
        sim, renderer = renderer_for(world, Pose2(5.0, 10.0))
        frame = renderer.render(sim)
        assert frame.depth_m is not None
        assert np.isinf(frame.depth_m[5:60, 400]).any()  # sky straight up
        trunk = 9.0 - 0.15 - 5.2
        assert frame.depth_m[300, 400] == pytest.approx(trunk, abs=0.01)
        assert frame.image[300, 400] > 0


class TestLight:
    def test_a_lamp_switched_off_darkens_the_room(self) -> None:
        lit = room(lamps=(Lamp((4.0, 3.0)),), lighting=dataclasses.replace(
            World.__dataclass_fields__["lighting"].default, ambient=0.3))
        dark = dataclasses.replace(lit, lamps=(Lamp((4.0, 3.0), on=False),))
        (sim_lit, lit_renderer), (sim_dark, dark_renderer) = (
            renderer_for(w, Pose2(1.0, 3.0)) for w in (lit, dark))
        under = [(4.0, 3.0)]
        assert lit_renderer.scene.light.at(under)[0] > 2.5 * dark_renderer.scene.light.at(under)[0]
        lit_image = lit_renderer.render(sim_lit).image
        dark_image = dark_renderer.render(sim_dark).image
        assert lit_image.mean() > 1.3 * dark_image.mean()

    def test_a_window_lights_its_side_of_the_wall(self) -> None:
        world = room(pictures=(Picture((5.0, 5.8), "window_wide", 1.5),),
                     lighting=dataclasses.replace(
                         World.__dataclass_fields__["lighting"].default, ambient=0.2))
        _, renderer = renderer_for(world, Pose2(1.0, 3.0))
        light = renderer.scene.light
        assert light.at([(5.0, 5.0)])[0] > 2 * light.at([(5.0, 1.0)])[0]
