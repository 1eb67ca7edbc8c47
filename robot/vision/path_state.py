"""The robot's state with respect to the route: lateral error y, angular error theta, progress s.

DESIGN.md sec. 5.5 and Courbon et al. 2008, sec. III-B/C: the line Gamma' runs
through the next key image's base position along its heading. With the current
base pose expressed in the next key image's base frame (x forward, y left):

* ``y`` = its y coordinate (signed lateral offset, left positive), m;
* ``theta`` = its yaw (robot yaw minus the key image's yaw, wrapped to (-pi, pi]);
* ``s`` = its x coordinate (along-track position, negative before the key image), m.

The vision gives the pose of the current *level camera* in the next key image's
level camera frame (:mod:`shared.camera_mount`); the mount maps it to the bases:
``T_bn_bc = T_base_level T_ln_lc T_base_level^-1``.

Two estimators:

* :func:`state_from_views`, three views (reference sec. 1.2): the relative pose
  current-next (:func:`robot.vision.epipolar.relative_pose`), then a metric planar
  resection against the key pair's points (:mod:`robot.vision.key_pair`,
  :mod:`robot.vision.resection`); the scale comes from the teach odometry
  between the two key images.
* :func:`state_from_two_views`, the fallback with no usable key pair: the relative
  pose current-next with a caller-supplied distance between the two optical
  centres (e.g. the teach spacing minus the odometric distance driven since the
  previous key image). Its y error is the distance error times sin of the
  bearing of the key image, plus the direction error times the distance.

A ground-plane scale (known camera height, Clement et al. 2015) was not built:
the simulator's worlds carry no floor texture, so it could not be measured.

Bearings come from :func:`robot.vision.bearings.level_bearings`; pass only the
rows it marks valid. Measured accuracy and time: :mod:`tools.bench.state`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from robot.config import PathStateConfig
from robot.vision.epipolar import EpipolarFit, check_bearings, relative_pose
from robot.vision.key_pair import KeyPairGeometry
from robot.vision.resection import resect_planar
from shared.camera_mount import transform_base_level
from shared.config import CameraMountConfig
from shared.errors import ShapeError, check_shape

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class PathCoordinates:
    """The current base pose in the next key image's base frame, as path coordinates.

    Attributes:
        s_m: along-track position, negative before the key image, m.
        y_m: lateral offset from the key image's line, left positive, m.
        theta_rad: yaw relative to the key image's heading, rad in (-pi, pi].
    """

    s_m: float
    y_m: float
    theta_rad: float


@dataclass(frozen=True, eq=False)
class PathState:
    """The state the control law regulates, with how it was obtained.

    Attributes:
        y_m: lateral error, left positive, m (0 when not ok).
        theta_rad: angular error (robot yaw minus the next key image's yaw), rad.
        s_m: along-track position relative to the next key image (negative before it), m.
        ok: the estimate is usable.
        scale_source: "three-view", "two-view" or "none" (not ok).
        n_inliers: epipolar inliers between the current and next views.
        n_points: key-pair points consistent with the current pose (0 for two views).
        T_next_current: (4, 4) float64 current level camera -> next key image's level
            camera, m (identity when not ok).
        inlier_mask: (K,) bool over the K matches given, those consistent with the
            epipolar geometry of the estimate (of the two-view fit when not ok); the
            paper's image errors are measured on them.
    """

    y_m: float
    theta_rad: float
    s_m: float
    ok: bool
    scale_source: str
    n_inliers: int
    n_points: int
    T_next_current: FloatArray = field(default_factory=lambda: np.eye(4))
    inlier_mask: npt.NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))


def path_coordinates(T_next_current: FloatArray, mount: CameraMountConfig) -> PathCoordinates:
    """Path coordinates (s, y, theta) of the current base from the level cameras' relative pose.

    Args:
        T_next_current: (4, 4) current level camera -> next key image's level camera, m.
            Only its planar part is used (any tilt is ignored).
        mount: where the camera sits on the robot.

    Returns:
        The coordinates.

    Raises:
        ShapeError: ``T_next_current`` is not (4, 4).
    """
    check_shape("T_next_current", np.shape(T_next_current), (4, 4))
    T_base_level = transform_base_level(mount)
    T = T_base_level @ np.asarray(T_next_current, dtype=np.float64) @ np.linalg.inv(T_base_level)
    return PathCoordinates(s_m=float(T[0, 3]), y_m=float(T[1, 3]),
                           theta_rad=math.atan2(T[1, 0], T[0, 0]))


def _pose(R: FloatArray, t: FloatArray) -> FloatArray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


def _state(T: FloatArray, mount: CameraMountConfig, ok: bool, source: str, fit: EpipolarFit,
           n_points: int, inlier_mask: npt.NDArray[np.bool_]) -> PathState:
    if not ok:
        return PathState(0.0, 0.0, 0.0, ok=False, scale_source="none", n_inliers=fit.n_inliers,
                         n_points=n_points, inlier_mask=inlier_mask)
    c = path_coordinates(T, mount)
    return PathState(y_m=c.y_m, theta_rad=c.theta_rad, s_m=c.s_m, ok=True, scale_source=source,
                     n_inliers=fit.n_inliers, n_points=n_points, T_next_current=T,
                     inlier_mask=inlier_mask)


def state_from_views(
    bearings_current: FloatArray, bearings_next: FloatArray, feature_idx_next: npt.ArrayLike,
    key_pair: KeyPairGeometry, mount: CameraMountConfig, rng: np.random.Generator,
    config: PathStateConfig,
) -> PathState:
    """The state from the current view, the next key image and the key pair's points.

    Args:
        bearings_current: (K, 3) unit rays of the current-next matches, current level frame.
        bearings_next: (K, 3) the same matches in the next key image's level frame.
        feature_idx_next: (K,) the next key image's feature index of each match (to
            find the key pair's points).
        key_pair: the structure of the next key image and the previous one (or the
            one after next), :func:`robot.vision.key_pair.key_pair_geometry`.
        mount: where the camera sits on the robot.
        rng: draws the RANSAC samples.
        config: thresholds.

    Returns:
        The state; ``ok`` is False (an expected outcome) when the relative pose or
        the key pair is not ok, or too few points are seen.

    Raises:
        ShapeError: the arrays disagree in shape.
        DegenerateGeometryError: a bearing is not a finite unit vector.
    """
    fc = check_bearings("bearings_current", bearings_current)
    fn = check_bearings("bearings_next", bearings_next, len(fc))
    idx = np.asarray(feature_idx_next, dtype=np.int64)
    if idx.shape != (len(fc),):
        raise ShapeError(f"feature_idx_next: expected shape ({len(fc)},), got {idx.shape}")
    fit = relative_pose(fc, fn, rng, config.pose_before_resection)
    if not (fit.ok and key_pair.ok):
        return _state(np.eye(4), mount, False, "none", fit, 0, fit.inlier_mask)
    rows, found = key_pair.points_for(idx)
    points = np.where(found[:, None], key_pair.points_n[rows], np.nan)
    resection = resect_planar(fc, fn, points, fit.inlier_mask, fit.R_b_a, fit.t_b_a, config)
    return _state(resection.T_n_c, mount, resection.ok, "three-view", fit,
                  resection.n_point_inliers, resection.epipolar_inlier_mask)


def state_from_two_views(
    bearings_current: FloatArray, bearings_next: FloatArray, distance_m: float,
    mount: CameraMountConfig, rng: np.random.Generator, config: PathStateConfig,
) -> PathState:
    """The state from the current view and the next key image, with a known distance.

    Args:
        bearings_current: (K, 3) unit rays of the current-next matches, current level frame.
        bearings_next: (K, 3) the same matches in the next key image's level frame.
        distance_m: distance between the current and the next key image's optical
            centres, from outside the images (odometry), m (>= 0).
        mount: where the camera sits on the robot.
        rng: draws the RANSAC samples.
        config: thresholds.

    Returns:
        The state; ``ok`` is False (an expected outcome) when the relative pose is not ok.

    Raises:
        ShapeError: the arrays disagree in shape.
        DegenerateGeometryError: a bearing is not a finite unit vector.
        ValueError: ``distance_m`` is negative or not finite.
    """
    if not (math.isfinite(distance_m) and distance_m >= 0):
        raise ValueError(f"distance_m must be finite and >= 0, got {distance_m}")
    fc = check_bearings("bearings_current", bearings_current)
    fn = check_bearings("bearings_next", bearings_next, len(fc))
    fit = relative_pose(fc, fn, rng, config.relative_pose)
    return _state(_pose(fit.R_b_a, distance_m * fit.t_b_a), mount, fit.ok, "two-view", fit, 0,
                  fit.inlier_mask)
