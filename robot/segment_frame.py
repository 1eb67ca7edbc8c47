"""Where the robot is relative to a route segment: the key image's line, its arc, the next line.

Frames (DESIGN.md sec. 4): a key image's *base frame* has its origin where the
robot's base was when the key image was taken, x along the robot's heading then,
y to the left. The paper's state (s, y, theta) is the robot's planar pose in the
base frame of the key image it heads for (Courbon et al. 2008, sec. III-C, eq. 1;
:class:`robot.vision.path_state.PathCoordinates`): y, theta are measured from the
line Gamma' through that key image along its heading.

Three conversions live here:

* :func:`relative_pose` and :func:`segment_curvature_1_m` read the teach odometry
  between two key images (``Keyframe.odom_pose``, ``Keyframe.distance_m``);
* :func:`coordinates_in_next_segment` moves (s, y, theta) from one key image's
  frame to the next one's when the robot switches key images;
* :func:`arc_coordinates` measures (s, y, theta) from the circular arc of the teach
  path's curvature that ends at the key image tangent to its heading, instead of
  from the straight line Gamma'. The curvature feed-forward law
  (:func:`robot.control_law.steer` with ``law = "paper+ff"``) regulates these, so
  that in a turn it follows the taught arc instead of cutting towards Gamma'.
"""

from __future__ import annotations

import math

from robot.vision.path_state import PathCoordinates
from shared.errors import DegenerateGeometryError
from shared.pose import Pose2


def wrap_angle(angle_rad: float) -> float:
    """The angle wrapped to (-pi, pi], rad."""
    wrapped = math.remainder(angle_rad, math.tau)
    return math.pi if wrapped == -math.pi else wrapped


def relative_pose(pose_from: Pose2, pose_to: Pose2) -> Pose2:
    """``pose_to`` expressed in the frame of ``pose_from`` (both in one common frame).

    Args:
        pose_from: e.g. a key image's teach odometry pose.
        pose_to: in the same frame, e.g. the next key image's.

    Returns:
        ``pose_to`` in ``pose_from``'s frame, yaw in (-pi, pi].
    """
    x0, y0, yaw0 = pose_from
    dx, dy = pose_to[0] - x0, pose_to[1] - y0
    c, s = math.cos(yaw0), math.sin(yaw0)
    return Pose2(c * dx + s * dy, -s * dx + c * dy, wrap_angle(pose_to[2] - yaw0))


def segment_curvature_1_m(pose_from: Pose2, pose_to: Pose2, length_m: float) -> float:
    """Mean curvature of the teach path between two key images: heading change over length.

    Args:
        pose_from: teach odometry pose of the first key image.
        pose_to: teach odometry pose of the second key image, same frame.
        length_m: odometric distance driven between them, m (``Keyframe.distance_m``
            difference).

    Returns:
        Curvature, 1/m, positive when the path turns left (counter-clockwise).

    Raises:
        DegenerateGeometryError: ``length_m`` is not > 0.
    """
    if not length_m > 0:
        raise DegenerateGeometryError(
            f"segment length must be > 0 m to give a curvature, got {length_m} m")
    return wrap_angle(pose_to[2] - pose_from[2]) / length_m


def coordinates_in_next_segment(
    coords: PathCoordinates, next_in_current: Pose2
) -> PathCoordinates:
    """Re-express the robot's (s, y, theta) in the base frame of the following key image.

    Args:
        coords: the robot's pose in the current key image's base frame.
        next_in_current: the following key image's pose in the current key image's
            base frame (:func:`relative_pose` of their teach odometry poses).

    Returns:
        The robot's pose in the following key image's base frame.
    """
    xk, yk, yawk = next_in_current
    c, s = math.cos(yawk), math.sin(yawk)
    dx, dy = coords.s_m - xk, coords.y_m - yk
    return PathCoordinates(s_m=c * dx + s * dy, y_m=-s * dx + c * dy,
                           theta_rad=wrap_angle(coords.theta_rad - yawk))


def arc_coordinates(coords: PathCoordinates, curvature_1_m: float) -> PathCoordinates:
    """The robot's coordinates relative to the arc that ends at the key image.

    The arc has constant curvature c, passes through the key image's origin tangent
    to its x axis, and so has its centre at (0, 1/c) in the key image's base frame.

    Args:
        coords: the robot's pose in the key image's base frame (line coordinates).
        curvature_1_m: c, 1/m, positive for a left turn; 0 returns ``coords``.

    Returns:
        s_m: arc length from the key image to the robot's closest point on the
        circle (negative before it); y_m: signed distance from the circle, left
        positive (for c > 0, towards the centre); theta_rad: heading relative to the
        circle's tangent at that point.

    Raises:
        DegenerateGeometryError: the robot is at the centre of the circle, where no
            closest point exists.
    """
    c = curvature_1_m
    if c == 0.0:
        return coords
    along, across = c * coords.s_m, 1.0 - c * coords.y_m
    radius_scaled = math.hypot(across, along)  # |c| times the distance to the centre
    if radius_scaled < 1e-9:
        raise DegenerateGeometryError(
            f"robot at the centre of the teach arc (curvature {c:.3g} 1/m, "
            f"s = {coords.s_m:.3g} m, y = {coords.y_m:.3g} m)")
    tangent_rad = math.atan2(along, across)
    # (1 - r|c|) / c without cancellation: 1 - sqrt(a) = (1 - a) / (1 + sqrt(a)).
    y_arc = (2.0 * coords.y_m - c * (coords.y_m**2 + coords.s_m**2)) / (1.0 + radius_scaled)
    return PathCoordinates(s_m=tangent_rad / c, y_m=y_arc,
                           theta_rad=wrap_angle(coords.theta_rad - tangent_rad))
