from __future__ import annotations

import dataclasses
import math
import threading
from pathlib import Path

import cv2
import numba
import numpy as np
import pytest

from shared.aria.p3at import SONAR_POSES
from shared.camera_model import CameraModel
from shared.config import CameraMountConfig
from shared.pose import Pose2
from sim._geometry import segments_cross
from sim.config import EmulatorConfig, PeopleConfig, RenderConfig, SensorConfig, SimConfig
from sim.decor import PlacedObject
from sim.pioneer.sonar import SonarRing
from sim.renderer import FisheyeRenderer, camera_pose_world, rotation_base_cam, set_render_threads
from sim.simulation import Simulation
from sim.topdown import _FURNITURE, MapCanvas, TopDownMap, draw_topdown
from sim.world import LandmarkDensity, World, load_world
from tests.sim.rooms import box_room
from tools.bench.corners import picture_corner_errors_px


def poster_room(folder: Path) -> World:
    """A 6 x 4 m room with white walls and four black posters (a texture set of its own)."""
    cv2.imwrite(str(folder / "white.png"), np.full((16, 16), 230, np.uint8))
    cv2.imwrite(str(folder / "black.png"), np.full((64, 64), 20, np.uint8))
    entry = 'size_m = [{}, {}]\nkind = "{}"\nsource = "test"\nlicence = "CC0-1.0"\n'
    (folder / "textures.toml").write_text(
        '[white]\nfile = "white.png"\ntiles = true\n' + entry.format(1.0, 1.0, "wall")
        + '\n[black]\nfile = "black.png"\n' + entry.format(0.5, 0.5, "picture"))
    walls = "\n".join(
        f'    {{ start = {a}, end = {b}, height_m = 2.5, texture = "white" }},'
        for a, b in [([0, 0], [6, 0]), ([6, 0], [6, 4]), ([6, 4], [0, 4]), ([0, 4], [0, 0])])
    (folder / "world.toml").write_text(f"""name = "posters"
texture_set = "textures.toml"
start = {{ x_m = 1.0, y_m = 2.0 }}
walls = [
{walls}
]
ceilings = [{{ min_corner = [0.0, 0.0], max_corner = [6.0, 4.0], height_m = 2.5 }}]
lamps = [{{ center = [3.0, 2.0] }}]
pictures = [
    {{ at = [5.8, 1.0], texture = "black", height_m = 1.0 }},
    {{ at = [5.8, 2.5], texture = "black", height_m = 0.6 }},
    {{ at = [3.0, 3.8], texture = "black", height_m = 1.2 }},
    {{ at = [3.0, 0.2], texture = "black", height_m = 0.8 }},
]
landmarks = {{ wall_per_m2 = 0.0, furniture_per_m2 = 0.0, ceiling_per_m2 = 0.0 }}
""")
    return load_world(folder / "world.toml")


def make(
    config: SimConfig | None = None, pose: Pose2 | None = None
) -> tuple[Simulation, FisheyeRenderer]:
    config = config or SimConfig()
    sim = Simulation(load_world(config.world), config)
    if pose is not None:
        sim.place_robot(pose)
    return sim, FisheyeRenderer.for_simulation(sim, CameraModel.default())


CORRIDOR = Pose2(8.0, 10.0, 0.0)  # lab: middle of the west part of the corridor, facing east


class TestRotationBaseCam:
    def test_level_camera_looks_forward_x_right_y_down(self) -> None:
        R = rotation_base_cam(CameraMountConfig())
        np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-12)  # optical axis -> forward
        np.testing.assert_allclose(
            R @ [1, 0, 0], [0, -1, 0], atol=1e-12
        )  # image right -> robot right
        np.testing.assert_allclose(R @ [0, 1, 0], [0, 0, -1], atol=1e-12)  # image down -> down

    def test_yaw_and_pitch(self) -> None:
        left = rotation_base_cam(CameraMountConfig(yaw_deg=90.0))
        np.testing.assert_allclose(left @ [0, 0, 1], [0, 1, 0], atol=1e-12)
        up = rotation_base_cam(CameraMountConfig(pitch_deg=30.0))
        np.testing.assert_allclose(up @ [0, 0, 1], [math.cos(math.radians(30)), 0, 0.5], atol=1e-12)

    def test_is_a_rotation(self) -> None:
        R = rotation_base_cam(CameraMountConfig(yaw_deg=12.0, pitch_deg=-7.0, roll_deg=3.0))
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)


def test_camera_pose_world_places_the_optical_centre() -> None:
    mount = CameraMountConfig(x_m=0.2, y_m=0.0, height_m=0.3)
    T = camera_pose_world((1.0, 2.0, math.pi / 2), mount)
    np.testing.assert_allclose(T[:3, 3], [1.0, 2.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [0.0, 1.0, 0.0], atol=1e-12)  # looks along +y


class TestRender:
    def test_picture_corners_in_view_agree_with_the_camera_model(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        frame = renderer.render(sim)
        assert frame.image.shape == (600, 800) and frame.image.dtype == np.uint8
        assert frame.visible_ids.shape[0] > 20
        corners = renderer.scene.picture_corners_w.reshape(-1, 3)[frame.visible_ids]
        T = frame.T_world_cam
        pixels, valid = CameraModel.default().project((corners - T[:3, 3]) @ T[:3, :3])
        assert valid.all()
        np.testing.assert_allclose(pixels, frame.visible_pixels_xy, atol=1e-9)
        assert np.all(np.diff(frame.visible_distances_m) >= 0)  # near to far
        assert frame.depth_m is not None
        assert np.isinf(frame.depth_m[0, 0]) and 0.3 < frame.depth_m[560, 400] < 1.5  # floor

    def test_outside_the_image_circle_is_black(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        image = renderer.render(sim).image
        assert image[0, 0] == image[0, -1] == image[-1, 0] == image[-1, -1] == 0
        assert image[300, 400] > 0

    def test_textured_corners_land_where_the_camera_model_projects_them(
        self, tmp_path: Path
    ) -> None:
        world = poster_room(tmp_path)
        quiet = dataclasses.replace(
            SimConfig(), render=RenderConfig(illumination_amplitude=0.0),
            sensor=SensorConfig.ideal())
        sim = Simulation(world, quiet)
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        errors = []
        for x, y, yaw in [(1.0, 2.0, 0.0), (2.0, 2.0, 20.0), (3.0, 2.0, -40.0), (4.0, 2.0, -10.0)]:
            sim.place_robot(Pose2(x, y, math.radians(yaw)))
            frame = renderer.render(sim)
            errors.append(picture_corner_errors_px(
                frame.image, CameraModel.default(), frame.T_world_cam,
                renderer.scene.picture_corners_w, frame.visible_ids))
        found = np.concatenate(errors)
        assert found.shape[0] >= 30
        assert np.median(found) < 0.5
        assert np.percentile(found, 90) < 1.0

    def test_no_visible_corner_is_behind_a_wall(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        frame = renderer.render(sim)
        walls = sim.world.walls
        a = np.array([w.start for w in walls])
        b = np.array([w.end for w in walls])
        cam = frame.T_world_cam[:3, 3]
        for p in renderer.scene.picture_corners_w.reshape(-1, 3)[frame.visible_ids]:
            # Stop just short of the corner: the wall carrying it does not count.
            end = cam[:2] + (p[:2] - cam[:2]) * (
                1.0 - 0.12 / max(np.hypot(*(p[:2] - cam[:2])), 0.12)
            )
            assert not segments_cross(cam[:2], end, a, b).any()

    def test_a_person_in_front_shows_up(self) -> None:
        config = dataclasses.replace(SimConfig(), people=PeopleConfig(count=1),
                                     sensor=SensorConfig.ideal())
        sim, renderer = make(config, pose=CORRIDOR)
        sim.people.place(0, (9.21, 10.0), (5.0, 10.0))  # walking towards the robot
        sim.step()
        with_person = renderer.render(sim)
        sim.people.place(0, (1.0, 10.0), (1.0, 10.0))  # behind the robot
        without = renderer.render(sim)
        centre = (slice(150, 330), slice(385, 415))
        changed = np.abs(with_person.image[centre].astype(float) - without.image[centre])
        assert np.mean(changed > 5) > 0.7  # the person covers the middle of the image


class TestLegacyPatches:
    def test_harris_finds_the_patches_where_ground_truth_says(self) -> None:
        world = box_room(density=LandmarkDensity(wall_per_m2=8.0, furniture_per_m2=0.0,
                                                 ceiling_per_m2=0.0))
        sim = Simulation(world, SimConfig())
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        frame = renderer.render(sim)
        assert frame.visible_ids.shape[0] > 50
        idx = np.searchsorted(sim.landmarks.ids, frame.visible_ids)
        T = frame.T_world_cam
        points_c = (sim.landmarks.positions_w[idx] - T[:3, 3]) @ T[:3, :3]
        pixels, _ = CameraModel.default().project(points_c)
        np.testing.assert_allclose(pixels, frame.visible_pixels_xy, atol=1e-9)
        corners = cv2.goodFeaturesToTrack(
            frame.image, maxCorners=2000, qualityLevel=0.005, minDistance=3, useHarrisDetector=True
        ).reshape(-1, 2)
        truth = frame.visible_pixels_xy[frame.visible_distances_m < 3.0]
        nearest = np.min(np.linalg.norm(truth[:, None, :] - corners[None, :, :], axis=2), axis=1)
        assert np.median(nearest) < 1.5


class TestNoise:
    def test_deterministic_for_a_seed(self) -> None:
        images = []
        for seed in (3, 3, 4):
            sim, renderer = make(dataclasses.replace(SimConfig(), seed=seed), pose=CORRIDOR)
            images.append(renderer.render(sim).image)
        assert np.array_equal(images[0], images[1])
        assert not np.array_equal(images[0], images[2])

    def test_noise_and_illumination(self) -> None:
        still = RenderConfig(illumination_amplitude=0.0)
        quiet = dataclasses.replace(SimConfig(), render=still, sensor=SensorConfig.ideal())
        sim, renderer = make(quiet, pose=CORRIDOR)
        a, b = renderer.render(sim).image, renderer.render(sim).image
        assert np.array_equal(a, b)
        noisy = dataclasses.replace(SimConfig(), render=still, sensor=dataclasses.replace(
            SensorConfig.ideal(), read_noise_grey=3.0))
        sim, renderer = make(noisy, pose=CORRIDOR)
        diff = renderer.render(sim).image.astype(float) - a.astype(float)
        inside = a > 0
        assert 2.0 < diff[inside].std() < 4.5
        lit = dataclasses.replace(
            SimConfig(), render=RenderConfig(illumination_amplitude=0.2, illumination_period_s=40.0)
        )
        sim, renderer = make(lit)
        gains = [renderer.illumination_gain(t * 10**9) for t in range(0, 40)]
        assert max(gains) <= 1.2 + 1e-12 and min(gains) >= 0.8 - 1e-12
        assert max(gains) - min(gains) > 0.3


class TestRenderThreads:
    def test_the_image_does_not_depend_on_the_threads_or_on_concurrent_callers(self) -> None:
        if numba.config.NUMBA_NUM_THREADS < 2:
            pytest.skip("numba started one thread: nothing to share")
        _, renderer = make(dataclasses.replace(SimConfig(), sensor=SensorConfig.ideal()),
                           CORRIDOR)
        T = camera_pose_world(CORRIDOR, renderer.mount)
        before = numba.get_num_threads()
        try:
            set_render_threads(1)
            alone = renderer.trace(T, CORRIDOR.yaw_rad)
            set_render_threads(2)
            shared = renderer.trace(T, CORRIDOR.yaw_rad)
        finally:
            set_render_threads(before)
        results: list[tuple[np.ndarray, np.ndarray]] = []
        callers = [threading.Thread(
            target=lambda: results.append(renderer.trace(T, CORRIDOR.yaw_rad)))
            for _ in range(3)]
        for caller in callers:
            caller.start()
        for caller in callers:
            caller.join()
        assert len(results) == 3
        for grey, depth in [shared, *results]:
            np.testing.assert_array_equal(grey, alone[0])
            np.testing.assert_array_equal(depth, alone[1])


class TestObjectsPlacedWhileRunning:
    def test_a_box_placed_mid_run_is_drawn_heard_and_gone_once_removed(self) -> None:
        config = dataclasses.replace(SimConfig(), sensor=SensorConfig.ideal())
        sim = Simulation(box_room((12.0, 6.0)), config)  # the robot at (6, 3) facing +x
        camera = CameraModel.default()
        renderer = FisheyeRenderer.for_simulation(sim, camera)
        ring = SonarRing(sim.space, EmulatorConfig(sonar_noise_m=0.0), np.random.default_rng(0))
        sim.step()
        before = renderer.render(sim)
        kept_map = TopDownMap(sim)  # a video's: made before the box, its layers drawn once
        box = sim.add_object(PlacedObject("box", (8.0, 3.0), (0.5, 0.5), 0.8))
        sim.step()
        with_box = renderer.render(sim)
        heard = ring.range_m(3, sim.body.pose_w)
        (u, v), = MapCanvas(sim).px([(8.0, 3.0)])
        assert tuple(draw_topdown(sim, with_box, 180.0)[v, u]) == _FURNITURE  # on the map too
        assert tuple(kept_map.draw(sim, with_box, 180.0)[v, u]) == _FURNITURE
        sim.remove_object(box)
        sim.step()
        after = renderer.render(sim)
        assert tuple(kept_map.draw(sim, after, 180.0)[v, u]) != _FURNITURE

        # The middle of the box's front face, x = 7.75 m, 0.4 m up.
        T = with_box.T_world_cam
        face_w = np.array([7.75, 3.0, 0.4])
        pix, ok = camera.project(((face_w - T[:3, 3]) @ T[:3, :3])[None])
        assert ok[0]
        col, row = np.round(pix[0]).astype(int)
        patch = (slice(row - 5, row + 6), slice(col - 5, col + 6))
        distance = float(np.linalg.norm(face_w - T[:3, 3]))
        assert with_box.depth_m[row, col] == pytest.approx(distance, rel=0.03)
        assert before.depth_m[row, col] > distance + 1.0  # the far wall, 4 m on
        changed = np.abs(with_box.image[patch].astype(float) - before.image[patch])
        assert changed.mean() > 5.0
        assert after.depth_m[row, col] == pytest.approx(before.depth_m[row, col])
        assert np.abs(after.image[patch].astype(float) - before.image[patch]).mean() < 2.0

        sonar_x = sim.body.pose_w[0] + SONAR_POSES[3][0]
        assert heard == pytest.approx(7.75 - sonar_x, abs=0.01)
        assert ring.range_m(3, sim.body.pose_w) > 5.0 - 0.01  # the far wall, 5.6 m: none
