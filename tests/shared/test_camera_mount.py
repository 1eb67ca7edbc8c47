"""Tests of shared/camera_mount.py: the camera's pose on the robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.camera_mount import (
    R_BASE_LEVEL,
    camera_pose_world,
    rotation_base_cam,
    rotation_level_cam,
    transform_base_level,
)
from shared.config import CameraMountConfig


class TestRotationLevelCam:
    def test_level_mount_is_the_identity(self) -> None:
        np.testing.assert_allclose(rotation_level_cam(CameraMountConfig()), np.eye(3), atol=1e-15)

    def test_pitched_camera_axis_lands_above_the_level_axis(self) -> None:
        R = rotation_level_cam(CameraMountConfig(pitch_deg=10.0))
        axis = R @ [0.0, 0.0, 1.0]  # optical axis in the level frame (y down)
        pitch = math.radians(10.0)
        np.testing.assert_allclose(axis, [0.0, -math.sin(pitch), math.cos(pitch)], atol=1e-12)

    def test_composes_with_the_base_rotation(self) -> None:
        mount = CameraMountConfig(yaw_deg=5.0, pitch_deg=-3.0, roll_deg=2.0)
        np.testing.assert_allclose(R_BASE_LEVEL @ rotation_level_cam(mount),
                                   rotation_base_cam(mount), atol=1e-15)


class TestTransformBaseLevel:
    def test_origin_is_the_optical_centre(self) -> None:
        mount = CameraMountConfig(x_m=0.2, y_m=-0.05, height_m=0.3, pitch_deg=7.0)
        T = transform_base_level(mount)
        np.testing.assert_allclose(T[:3, 3], [0.2, -0.05, 0.3])
        np.testing.assert_allclose(T[:3, :3], R_BASE_LEVEL)
        # Agrees with the camera's world pose for a robot at the origin.
        np.testing.assert_allclose(camera_pose_world((0.0, 0.0, 0.0), mount)[:3, 3], T[:3, 3],
                                   atol=1e-15)

    def test_level_frame_is_read_only(self) -> None:
        with pytest.raises(ValueError, match="read-only"):
            R_BASE_LEVEL[0, 0] = 2.0
