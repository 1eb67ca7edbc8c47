"""People as textured figures (sim/person_figure.py), drawn through the camera model."""

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
from sim.config import PeopleConfig, SimConfig
from sim.person_figure import FigurePose, PersonFigures, PersonLook, draw_look
from sim.simulation import Simulation
from sim.texture_library import TextureLibrary
from tests.sim.rooms import box_room

CAMERA = CameraModel.default()
MOUNT = CameraMountConfig()
T_WORLD_CAM = camera_pose_world(Pose2(0.0, 0.0, 0.0), MOUNT)  # looks along world +x
R_CAM_WORLD = T_WORLD_CAM[:3, :3].T
CENTRE_W = T_WORLD_CAM[:3, 3]
BACKGROUND = 128


def figures(seed: int = 1) -> PersonFigures:
    return PersonFigures(CAMERA, TextureLibrary.builtin(), 110.0, np.random.default_rng(seed))


def facing_camera(distance_m: float, height_m: float = 1.75) -> FigurePose:
    """A person ``distance_m`` in front of the optical centre, facing it."""
    return FigurePose(float(CENTRE_W[0]) + distance_m, 0.0, math.pi, 0.0, height_m, 0.25)


def draw(fig: PersonFigures, pose: FigurePose, look: PersonLook,
         occluders: list[tuple[float, float]] | None = None) -> npt.NDArray[np.uint8]:
    image = np.full((CAMERA.height, CAMERA.width), BACKGROUND, dtype=np.uint8)
    fig.draw(image, pose, look, R_CAM_WORLD, CENTRE_W, occluders or [])
    return image


def pixel_of(x_m: float, y_m: float, z_m: float) -> tuple[float, float]:
    pixels, valid = CAMERA.project((np.array([[x_m, y_m, z_m]]) - CENTRE_W) @ R_CAM_WORLD.T)
    assert valid[0]
    return float(pixels[0, 0]), float(pixels[0, 1])


class TestDraw:
    def test_the_figure_stands_where_the_camera_model_projects_it(self) -> None:
        fig = figures()
        pose = facing_camera(3.0)
        image = draw(fig, pose, fig.look(0))
        changed = np.abs(image.astype(int) - BACKGROUND) > 3
        rows = np.flatnonzero(changed[:, 398:403].any(axis=1))
        _, top_v = pixel_of(pose.x_m - 0.1, 0.0, pose.height_m)  # the head's front top
        _, foot_v = pixel_of(pose.x_m - 0.075, 0.0, 0.0)  # the feet's front
        assert rows.min() == pytest.approx(top_v, abs=3.0)
        assert rows.max() == pytest.approx(foot_v, abs=3.0)
        columns = np.flatnonzero(changed[int(pixel_of(pose.x_m, 0.0, 1.1)[1])])
        left_u, _ = pixel_of(pose.x_m, 0.285, 1.1)  # the arms' outer side, at the waist
        right_u, _ = pixel_of(pose.x_m, -0.285, 1.1)
        assert columns.min() == pytest.approx(left_u, abs=3.0)
        assert columns.max() == pytest.approx(right_u, abs=3.0)

    def test_textured_clothes_skin_and_hair_not_a_silhouette(self) -> None:
        fig = figures()
        pose = facing_camera(1.5)
        look = PersonLook(("clothing_denim", "clothing_striped", "skin", "hair", "person_face"),
                          (0.6, 1.0, 1.0, 0.5, 1.3), long_hair=False)
        image = draw(fig, pose, look).astype(float)
        u = round(pixel_of(pose.x_m, 0.0, 1.0)[0])

        def patch(z_m: float, lateral_m: float = 0.0) -> npt.NDArray[np.float64]:
            cu, cv = (round(p) for p in pixel_of(pose.x_m - 0.1, lateral_m, z_m))
            return image[cv - 3:cv + 4, cu - 3:cu + 4]

        shirt, legs, face = patch(1.2), patch(0.5, 0.09), patch(1.62)
        assert shirt.std() > 8  # stripes, folds: texture, not a flat fill
        assert face.mean() > legs.mean() + 30  # light skin above dark trousers
        assert abs(u - 400) <= 1
        back = dataclasses.replace(pose, heading_rad=0.0)  # seen from behind: hair, no face
        behind = draw(fig, back, look).astype(float)
        cu, cv = (round(p) for p in pixel_of(back.x_m - 0.1, 0.0, 1.68))
        assert behind[cv - 2:cv + 3, cu - 2:cu + 3].mean() < face.mean() - 30

    def test_a_wall_hides_it_and_a_desk_hides_only_the_legs(self) -> None:
        fig = figures()
        pose = facing_camera(3.0)
        look = fig.look(0)
        alone = draw(fig, pose, look)
        assert np.array_equal(draw(fig, pose, look, [(1.5, 2.5)]), np.full_like(alone, BACKGROUND))
        desk = draw(fig, pose, look, [(2.0, 0.75)])
        head_u, head_v = (round(p) for p in pixel_of(pose.x_m - 0.1, 0.0, 1.6))
        foot_u, foot_v = (round(p) for p in pixel_of(pose.x_m - 0.08, 0.09, 0.2))
        assert desk[head_v, head_u] == alone[head_v, head_u] != BACKGROUND
        assert desk[foot_v, foot_u] == BACKGROUND != alone[foot_v, foot_u]

    def test_a_depth_image_hides_it_per_pixel_on_a_float_canvas(self) -> None:
        fig = figures()
        pose = facing_camera(3.0)
        look = fig.look(0)
        alone = draw(fig, pose, look)
        _, waist_v = pixel_of(pose.x_m - 0.1, 0.0, 1.0)
        depth = np.full((CAMERA.height, CAMERA.width), np.inf, dtype=np.float32)
        depth[round(waist_v):] = 2.0  # something 2 m away below the waist
        canvas = np.full((CAMERA.height, CAMERA.width), float(BACKGROUND), dtype=np.float32)
        fig.draw(canvas, pose, look, R_CAM_WORLD, CENTRE_W, [], depth)
        head_u, head_v = (round(p) for p in pixel_of(pose.x_m - 0.1, 0.0, 1.6))
        foot_u, foot_v = (round(p) for p in pixel_of(pose.x_m - 0.08, 0.09, 0.2))
        assert canvas[head_v, head_u] == pytest.approx(alone[head_v, head_u], abs=0.5)
        assert canvas[foot_v, foot_u] == BACKGROUND != alone[foot_v, foot_u]
        assert canvas[head_v, head_u] != round(canvas[head_v, head_u])  # not rounded

    def test_the_light_where_it_stands_scales_it(self) -> None:
        fig = figures()
        pose = facing_camera(3.0)
        canvases = []
        for light in (1.0, 0.5):
            canvas = np.zeros((CAMERA.height, CAMERA.width), dtype=np.float32)
            fig.draw(canvas, pose, fig.look(0), R_CAM_WORLD, CENTRE_W, [], None, light)
            canvases.append(canvas)
        drawn = canvases[0] > 0
        assert drawn.sum() > 500
        np.testing.assert_allclose(canvases[1][drawn], 0.5 * canvases[0][drawn], rtol=1e-5)

    def test_a_figure_behind_the_camera_or_too_near_draws_nothing(self) -> None:
        fig = figures()
        behind = dataclasses.replace(facing_camera(-3.0), heading_rad=0.0)
        assert (draw(fig, behind, fig.look(0)) == BACKGROUND).all()


class TestLooks:
    def test_fixed_for_a_seed_and_varied_between_people(self) -> None:
        library = TextureLibrary.builtin()
        looks = [draw_look(np.random.default_rng(7), library) for _ in range(2)]
        assert looks[0] == looks[1]
        rng = np.random.default_rng(7)
        many = [draw_look(rng, library) for _ in range(12)]
        assert len({look.textures[1] for look in many}) >= 3  # several shirts
        assert len({round(look.greys[2], 2) for look in many}) == 12  # skin tones differ
        for look in many:
            for name in look.textures:
                assert library.get(name).kind == "person"

    def test_each_person_keeps_their_look(self) -> None:
        fig = figures(seed=3)
        first = [fig.look(k) for k in range(3)]
        assert [fig.look(k) for k in range(3)] == first


class TestInTheSimulation:
    def test_people_walk_facing_their_way_and_nearer_ones_hide_farther_ones(self) -> None:
        config = dataclasses.replace(SimConfig(seed=2), people=PeopleConfig(count=2))
        sim = Simulation(box_room(), config)
        sim.place_robot(Pose2(2.0, 3.0, 0.0))
        sim.people.place(0, (4.0, 3.0), (4.0, 5.0))  # walks towards +y
        sim.people.place(1, (6.0, 3.0), (6.0, 1.0))  # walks towards -y
        for _ in range(10):
            sim.step()
        np.testing.assert_allclose(sim.people.headings(), [math.pi / 2, -math.pi / 2], atol=1e-9)
        np.testing.assert_allclose(sim.people.walked_m(), [0.1, 0.1], atol=1e-9)
        sim.people.place(0, (4.0, 3.0), (4.0, 3.0))
        sim.people.place(1, (6.0, 3.3), (6.0, 3.3))  # behind the first, from the robot
        pose_w = sim.body.pose_w
        T = camera_pose_world(pose_w, config.camera_mount)
        fig = PersonFigures(CAMERA, TextureLibrary.builtin(), 110.0, np.random.default_rng(0))
        both = np.full((CAMERA.height, CAMERA.width), BACKGROUND, dtype=np.uint8)
        fig.draw_people(sim, both, T[:3, :3].T, T[:3, 3])
        near_only = np.full_like(both, BACKGROUND)
        fig.draw(near_only, FigurePose(4.0, 3.0, float(sim.people.headings()[0]),
                                       float(sim.people.walked_m()[0]), 1.75, 0.25),
                 fig.look(0), T[:3, :3].T, T[:3, 3], [])
        centre = (slice(200, 300), slice(395, 405))  # the near person's torso
        assert np.array_equal(both[centre], near_only[centre])
        assert (both != BACKGROUND).sum() > (near_only != BACKGROUND).sum()  # the far one shows
