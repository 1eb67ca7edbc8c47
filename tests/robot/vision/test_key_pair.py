"""Tests of robot/vision/key_pair.py: metric structure of two key images."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robot.config import PathStateConfig
from robot.vision.bearings import level_bearings
from robot.vision.key_pair import KeyPairGeometry, camera_baseline_level, key_pair_geometry
from shared.camera_mount import camera_pose_world, rotation_level_cam
from shared.config import CameraMountConfig
from shared.errors import DegenerateGeometryError, ShapeError
from sim.synthetic.corridor_scene import CorridorScene, SceneView, corridor_scene

CONFIG = PathStateConfig()


def level_pose_world(scene: CorridorScene, view: SceneView) -> np.ndarray:
    """(4, 4) T_world_level of a view."""
    T = camera_pose_world(view.pose_w, scene.mount)
    T[:3, :3] = T[:3, :3] @ rotation_level_cam(scene.mount).T
    return T


def previous_pair(scene: CorridorScene, rng: np.random.Generator,
                  config: PathStateConfig = CONFIG) -> KeyPairGeometry:
    R = rotation_level_cam(scene.mount)
    m = scene.previous_next
    return key_pair_geometry(
        level_bearings(scene.camera, scene.next.pixels_xy[m.idx_next], R).bearings,
        level_bearings(scene.camera, scene.previous.pixels_xy[m.idx_view], R).bearings,
        m.idx_next, scene.odom_next, scene.odom_previous, scene.mount, rng, config,
    )


class TestCameraBaselineLevel:
    def test_straight_ahead(self) -> None:
        t = camera_baseline_level((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), CameraMountConfig())
        np.testing.assert_allclose(t, [0.0, 0.0, -1.0], atol=1e-12)

    def test_a_turn_moves_the_camera_ahead_of_the_axle(self) -> None:
        # A quarter turn on the spot: the optical centres, 0.2 m ahead of the axle,
        # move from (0.2, 0) to (0, 0.2) while the base does not move at all.
        t = camera_baseline_level((0.0, 0.0, math.pi / 2), (0.0, 0.0, 0.0),
                                  CameraMountConfig(x_m=0.2))
        np.testing.assert_allclose(t, [0.2, 0.0, -0.2], atol=1e-12)


class TestKeyPairGeometry:
    def test_smoke(self, rng: np.random.Generator) -> None:
        pair = previous_pair(corridor_scene(rng), rng)
        assert pair.ok
        assert pair.points_n.shape == (len(pair.feature_idx), 3) and len(pair.feature_idx) > 30
        assert np.all(np.diff(pair.feature_idx) > 0)
        assert pair.baseline_m == pytest.approx(np.linalg.norm(pair.t_n_o))

    def test_shapes(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng)
        b = np.tile([0.0, 0.0, 1.0], (5, 1))
        with pytest.raises(ShapeError, match="feature_idx_next"):
            key_pair_geometry(b, b, np.arange(4), s.odom_next, s.odom_previous, s.mount, rng,
                              CONFIG)
        with pytest.raises(ShapeError, match="bearings_other"):
            key_pair_geometry(b, b[:4], np.arange(5), s.odom_next, s.odom_previous, s.mount, rng,
                              CONFIG)

    def test_known_points_and_baseline(self, rng: np.random.Generator) -> None:
        """1 px noise, 20 % outliers, 1 % odometric scale error; 10 corridors."""
        for _ in range(10):
            s = corridor_scene(rng)
            pair = previous_pair(s, rng)
            assert pair.ok
            T_n = level_pose_world(s, s.next)
            T_n_o = np.linalg.inv(T_n) @ level_pose_world(s, s.previous)
            assert pair.t_n_o == pytest.approx(T_n_o[:3, 3], abs=0.03)
            assert math.degrees(pair.odometry_disagreement_rad) < 3.0
            # The points of true inlier matches, against the truth in the next level frame.
            truth_w = s.points_w[s.next.point_ids[pair.feature_idx]]
            truth_n = (truth_w - T_n[:3, 3]) @ T_n[:3, :3]
            error = np.linalg.norm(pair.points_n - truth_n, axis=1)
            relative = error / np.linalg.norm(truth_n, axis=1)
            # The depth error is about sqrt(2) x 1 px / parallax: points near the direction
            # of travel (kept down to 2 degrees) are coarse, the others within a few per cent.
            to_other = truth_n - T_n_o[:3, 3]
            cos_parallax = np.sum(truth_n * to_other, axis=1) / (
                np.linalg.norm(truth_n, axis=1) * np.linalg.norm(to_other, axis=1))
            assert np.median(relative) < 0.1
            assert np.median(relative[cos_parallax < math.cos(math.radians(10.0))]) < 0.06

    def test_points_for(self, rng: np.random.Generator) -> None:
        pair = previous_pair(corridor_scene(rng), rng)
        missing = int(np.setdiff1d(np.arange(pair.feature_idx.max() + 2), pair.feature_idx)[0])
        rows, found = pair.points_for([pair.feature_idx[3], missing, pair.feature_idx[0]])
        assert found.tolist() == [True, False, True]
        assert rows[0] == 3 and rows[2] == 0

    def test_zero_odometric_baseline_is_degenerate(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng)
        b = np.tile([0.0, 0.0, 1.0], (5, 1))
        with pytest.raises(DegenerateGeometryError, match="apart by odometry"):
            key_pair_geometry(b, b, np.arange(5), s.odom_next, s.odom_next, s.mount, rng, CONFIG)

    def test_odometry_contradicting_the_images_is_not_ok(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng)
        # Swap the odometry: the previous key image would be ahead of the next one.
        swapped = dataclasses.replace(s, odom_previous=s.odom_next, odom_next=s.odom_previous)
        pair = previous_pair(swapped, rng)
        assert pair.fit.ok and not pair.ok
        assert math.degrees(pair.odometry_disagreement_rad) > 150.0
