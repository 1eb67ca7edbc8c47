from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest

from shared.camera_model import CameraModel
from shared.config import CameraMountConfig
from shared.pose import Pose2
from sim._geometry import segments_cross
from sim.config import PeopleConfig, RenderConfig, SensorConfig, SimConfig
from sim.renderer import FisheyeRenderer, camera_pose_world, rotation_base_cam
from sim.simulation import Simulation
from sim.world import load_world


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
    def test_frame_and_ground_truth_agree_with_the_camera_model(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        frame = renderer.render(sim)
        assert frame.image.shape == (600, 800) and frame.image.dtype == np.uint8
        assert frame.visible_ids.shape[0] > 100
        idx = np.searchsorted(sim.landmarks.ids, frame.visible_ids)
        T = frame.T_world_cam
        points_c = (sim.landmarks.positions_w[idx] - T[:3, 3]) @ T[:3, :3]
        pixels, valid = CameraModel.default().project(points_c)
        assert valid.all()
        np.testing.assert_allclose(pixels, frame.visible_pixels_xy, atol=1e-9)
        assert np.all(np.diff(frame.visible_distances_m) >= 0)  # near to far

    def test_outside_the_image_circle_is_black(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        image = renderer.render(sim).image
        assert image[0, 0] == image[0, -1] == image[-1, 0] == image[-1, -1] == 0
        assert image[300, 400] > 0

    def test_harris_finds_the_landmarks_where_ground_truth_says(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        frame = renderer.render(sim)
        corners = cv2.goodFeaturesToTrack(
            frame.image, maxCorners=2000, qualityLevel=0.005, minDistance=3, useHarrisDetector=True
        )
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.01)
        corners = cv2.cornerSubPix(frame.image, corners, (3, 3), (-1, -1), criteria).reshape(-1, 2)
        truth = frame.visible_pixels_xy[frame.visible_distances_m < 3.0]  # patches >= ~8 px
        assert truth.shape[0] > 30
        nearest = np.min(np.linalg.norm(truth[:, None, :] - corners[None, :, :], axis=2), axis=1)
        # Patches seen at grazing angles are squeezed to a few pixels: corners move up to ~2 px.
        assert np.mean(nearest < 2.5) > 0.85
        assert np.median(nearest) < 1.0

    def test_no_visible_landmark_is_behind_a_wall(self) -> None:
        sim, renderer = make(pose=CORRIDOR)
        frame = renderer.render(sim)
        walls = sim.world.walls
        a = np.array([w.start for w in walls])
        b = np.array([w.end for w in walls])
        cam = frame.T_world_cam[:3, 3]
        idx = np.searchsorted(sim.landmarks.ids, frame.visible_ids)
        for p in sim.landmarks.positions_w[idx]:
            # Stop just short of the landmark: the wall carrying it does not count.
            end = cam[:2] + (p[:2] - cam[:2]) * (
                1.0 - 0.05 / max(np.hypot(*(p[:2] - cam[:2])), 0.05)
            )
            assert not segments_cross(cam[:2], end, a, b).any()

    def test_a_person_in_front_hides_landmarks_and_shows_up(self) -> None:
        config = dataclasses.replace(SimConfig(), people=PeopleConfig(count=1),
                                     sensor=SensorConfig.ideal())
        sim, renderer = make(config, pose=CORRIDOR)
        sim.people.place(0, (9.21, 10.0), (5.0, 10.0))  # walking towards the robot
        sim.step()
        with_person = renderer.render(sim)
        sim.people.place(0, (1.0, 10.0), (1.0, 10.0))  # behind the robot
        without = renderer.render(sim)
        assert with_person.visible_ids.shape[0] < without.visible_ids.shape[0]
        centre = (slice(150, 330), slice(385, 415))
        changed = np.abs(with_person.image[centre].astype(float) - without.image[centre])
        assert np.mean(changed > 5) > 0.7  # the person covers the middle of the image

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
