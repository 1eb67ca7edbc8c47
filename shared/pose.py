"""The planar pose: where a robot base stands on the floor and which way it faces.

One type for every (x, y, yaw) in the code: the simulator's true pose, the base's
odometry, a key image's teach pose, a query pose of a benchmark. The frame is not
part of the type; names carry it (``pose_w`` in the world, ``odom_pose`` in the
odometry frame, DESIGN.md sec. 4). A ``NamedTuple``, so that it still unpacks as
``x, y, yaw = pose``, compares equal to a plain 3-tuple and goes into JSON and
numpy as three numbers.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["Pose2"]


class Pose2(NamedTuple):
    """A planar pose of the robot base.

    Attributes:
        x_m: x, m.
        y_m: y, m.
        yaw_rad: heading, counter-clockwise from +x, rad.
    """

    x_m: float
    y_m: float
    yaw_rad: float = 0.0
