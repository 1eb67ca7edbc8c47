"""Where the camera sits on the robot: the base <- camera and base <- level-camera transforms.

Frames (DESIGN.md section 4):

* base: x forward, y left, z up, origin on the floor under the robot's centre;
* camera: z along the optical axis, x right, y down in the image, origin at the
  optical centre;
* level camera: the camera's optical centre with the axes of a camera that looks
  straight forward with zero yaw, pitch and roll (x right, y down, z forward, all
  fixed to the base). On a flat floor its y axis stays vertical and its origin
  stays at ``height_m``, so two level frames differ by a rotation about y and a
  translation in the x-z plane: the "upright planar" motion of PoseLib's
  ``relpose_upright_planar_2pt``.

Used by the simulator's renderer (where the camera looks) and by the robot's
vision (bearings in the level frame, camera centres to base positions).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from shared.config import CameraMountConfig
from shared.pose import Pose2

FloatArray = npt.NDArray[np.float64]

#: (3, 3) ``R_base_level``: the level camera's axes (x right, y down, z forward) in the base frame.
R_BASE_LEVEL: FloatArray = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
R_BASE_LEVEL.setflags(write=False)


def rotation_base_cam(mount: CameraMountConfig) -> FloatArray:
    """Rotation taking camera-frame vectors into the robot (base) frame.

    Camera frame: z along the optical axis, x right, y down. Base frame: x
    forward, y left, z up. With zero yaw, pitch and roll the camera looks
    forward; yaw turns it left, pitch up, roll about its axis.

    Returns:
        (3, 3) float64 ``R_base_cam``.
    """
    yaw, pitch, roll = (math.radians(a) for a in (mount.yaw_deg, mount.pitch_deg, mount.roll_deg))
    cz, sz = math.cos(yaw), math.sin(yaw)
    cy, sy = math.cos(-pitch), math.sin(-pitch)
    cx, sx = math.cos(roll), math.sin(roll)
    Rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    Ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    Rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return Rz @ Ry @ Rx @ R_BASE_LEVEL


def rotation_level_cam(mount: CameraMountConfig) -> FloatArray:
    """Rotation taking camera-frame vectors into the level camera frame.

    Returns:
        (3, 3) float64 ``R_level_cam`` (the identity for a level, forward-looking camera).
    """
    return R_BASE_LEVEL.T @ rotation_base_cam(mount)


def transform_base_level(mount: CameraMountConfig) -> FloatArray:
    """The level camera frame's pose on the robot.

    Returns:
        (4, 4) float64 ``T_base_level`` (level-camera frame -> base frame): rotation
        :data:`R_BASE_LEVEL`, translation the optical centre ``(x_m, y_m, height_m)``.
    """
    T = np.eye(4)
    T[:3, :3] = R_BASE_LEVEL
    T[:3, 3] = (mount.x_m, mount.y_m, mount.height_m)
    return T


def camera_pose_world(pose_w: Pose2, mount: CameraMountConfig) -> FloatArray:
    """The camera's pose in the world for a robot pose.

    Args:
        pose_w: robot pose on the floor plan.
        mount: where the camera sits on the robot.

    Returns:
        (4, 4) float64 ``T_world_cam`` (camera frame -> world frame, z up, floor at 0).
    """
    x, y, yaw = pose_w
    c, s = math.cos(yaw), math.sin(yaw)
    R_world_base = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    T = np.eye(4)
    T[:3, :3] = R_world_base @ rotation_base_cam(mount)
    offset_base = np.array([mount.x_m, mount.y_m, mount.height_m])
    T[:3, 3] = np.array([x, y, 0.0]) + R_world_base @ offset_base
    return T
