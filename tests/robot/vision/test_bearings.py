"""Tests of robot/vision/bearings.py: pixels to unit bearings in the level frame."""

from __future__ import annotations

import numpy as np
import pytest

from robot.vision.bearings import level_bearings
from shared.camera_model import CameraModel
from shared.camera_mount import rotation_level_cam
from shared.config import CameraMountConfig
from shared.errors import ShapeError

CAMERA = CameraModel.default()


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


class TestLevelBearings:
    def test_smoke(self) -> None:
        out = level_bearings(CAMERA, [[399.5, 299.5]], np.eye(3))
        np.testing.assert_allclose(out.bearings, [[0.0, 0.0, 1.0]], atol=1e-12)
        assert out.valid.tolist() == [True]

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError, match="pixels_xy"):
            level_bearings(CAMERA, np.zeros((3, 3)), np.eye(3))
        with pytest.raises(ShapeError, match="R_level_cam"):
            level_bearings(CAMERA, np.zeros((3, 2)), np.eye(4))

    def test_rays_beyond_90_degrees_through_a_tilted_mount(self, rng: np.random.Generator) -> None:
        mount = CameraMountConfig(yaw_deg=4.0, pitch_deg=-12.0, roll_deg=1.5)
        R = rotation_level_cam(mount)
        # Rays up to 92 degrees off the optical axis, many behind the image plane (z < 0).
        theta = np.radians(np.concatenate([rng.uniform(0.0, 92.0, 100),
                                           rng.uniform(88.0, 92.0, 100)]))
        phi = rng.uniform(-np.pi, np.pi, 200)
        rays_c = np.column_stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                                  np.cos(theta)])
        pixels, valid = CAMERA.project(rays_c)
        assert valid.all() and np.count_nonzero(rays_c[:, 2] < 0) > 40
        out = level_bearings(CAMERA, pixels, R)
        assert out.valid.all()
        np.testing.assert_allclose(out.bearings, _unit(rays_c) @ R.T, atol=1e-9)

    def test_invalid_pixels_give_a_placeholder_row(self) -> None:
        out = level_bearings(CAMERA, [[0.0, 0.0], [399.5, 299.5], [-50.0, 10.0]], np.eye(3))
        assert out.valid.tolist() == [False, True, False]
        np.testing.assert_array_equal(out.bearings[~out.valid], [[0.0, 0.0, 1.0]] * 2)
        assert np.all(np.isfinite(out.bearings))
