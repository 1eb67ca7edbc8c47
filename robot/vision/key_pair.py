"""Metric structure of two key images: the scale of the three-view state estimate.

Reference visual-navigation.md, sec. 1.2, steps 1-2 and 5: the relative pose of
another key image o with respect to the next key image n from their matched
bearings (:func:`robot.vision.epipolar.relative_pose`), its length from the teach
odometry (the distance between the two optical centres, which differs from the
base's when the robot turned, because the camera sits ``x_m`` ahead of the axle),
then the common points triangulated in n's level frame, in metres.

The other key image is normally the previous one (i), as in the paper ("using the
current, desired and the former desired images"); on a path's first segment,
where there is none, the key image after next (i + 2) serves the same purpose.
This depends on the key images only, so it is computed once per segment (or at
teach time), not per frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from robot.config import PathStateConfig
from robot.vision.epipolar import EpipolarFit, check_bearings, relative_pose
from robot.vision.triangulation import triangulate_bearings
from shared.camera_mount import R_BASE_LEVEL
from shared.config import CameraMountConfig
from shared.errors import DegenerateGeometryError, ShapeError, check_shape
from shared.pose import Pose2

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Key images whose optical centres are closer than this (by odometry) are refused, m.
_MIN_BASELINE_M = 0.01


@dataclass(frozen=True, eq=False)
class KeyPairGeometry:
    """Points and poses of two key images in the next key image's level frame, in metres.

    Attributes:
        points_n: (M, 3) float64 triangulated points, next key image's level frame, m.
        feature_idx: (M,) int64 indices of the next key image's features the points
            belong to, strictly increasing.
        R_n_o: (3, 3) rotation, other key image's level frame -> next's.
        t_n_o: (3,) the other key image's optical centre in the next's level frame, m.
        baseline_m: distance between the two optical centres (teach odometry), m.
        fit: the relative pose the points were triangulated with.
        odometry_disagreement_rad: angle between the visual and the odometric
            direction of the baseline, rad.
        ok: the fit is ok, agrees with the odometry, and at least
            ``config.min_points`` points were triangulated.
    """

    points_n: FloatArray
    feature_idx: IntArray
    R_n_o: FloatArray
    t_n_o: FloatArray
    baseline_m: float
    fit: EpipolarFit
    odometry_disagreement_rad: float
    ok: bool

    def points_for(self, feature_idx_next: npt.ArrayLike) -> tuple[IntArray, npt.NDArray[np.bool_]]:
        """Look up the points of some of the next key image's features.

        Args:
            feature_idx_next: (K,) feature indices in the next key image.

        Returns:
            rows: (K,) int64 row of ``points_n`` per feature (0 where there is none).
            found: (K,) bool, the feature has a point.
        """
        idx = np.asarray(feature_idx_next, dtype=np.int64)
        check_shape("feature_idx_next", idx.shape, (None,))
        rows = np.searchsorted(self.feature_idx, idx)
        rows = np.minimum(rows, max(len(self.feature_idx) - 1, 0))
        found = (self.feature_idx[rows] == idx) if len(self.feature_idx) else np.zeros(
            idx.shape, dtype=bool)
        return np.where(found, rows, 0), found


def camera_baseline_level(odom_next: Pose2, odom_other: Pose2,
                          mount: CameraMountConfig) -> FloatArray:
    """The other key image's optical centre in the next key image's level frame, by odometry.

    Args:
        odom_next: odometry base pose of the next key image.
        odom_other: odometry base pose of the other key image, same odometry frame.
        mount: where the camera sits on the robot.

    Returns:
        (3,) float64 position, m (y = 0: both centres are at the camera's height).
    """
    xn, yn, yawn = odom_next
    xo, yo, yawo = odom_other
    offset = np.array([mount.x_m, mount.y_m])

    def rot(yaw: float) -> FloatArray:
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([[c, -s], [s, c]])

    # Both optical centres in the odometry frame, then in the next key image's base frame.
    centre_o = np.array([xo, yo]) + rot(yawo) @ offset
    centre_n = np.array([xn, yn]) + rot(yawn) @ offset
    in_base = rot(yawn).T @ (centre_o - centre_n)
    return R_BASE_LEVEL.T @ np.array([in_base[0], in_base[1], 0.0])


def key_pair_geometry(
    bearings_next: FloatArray, bearings_other: FloatArray, feature_idx_next: npt.ArrayLike,
    odom_next: Pose2, odom_other: Pose2, mount: CameraMountConfig, rng: np.random.Generator,
    config: PathStateConfig,
) -> KeyPairGeometry:
    """Triangulate the matches of two key images in the next key image's level frame.

    Args:
        bearings_next: (K, 3) unit rays of the matches in the next key image's level frame.
        bearings_other: (K, 3) unit rays of the same matches in the other key image's
            level frame (the previous key image, or the one after next).
        feature_idx_next: (K,) the next key image's feature index of each match.
        odom_next: teach odometry base pose of the next key image.
        odom_other: teach odometry base pose of the other key image, same frame.
        mount: where the camera sits on the robot.
        rng: draws the RANSAC samples.
        config: thresholds.

    Returns:
        The geometry; ``ok`` is False (an expected outcome) when the two views do
        not give a trustworthy structure.

    Raises:
        ShapeError: the arrays disagree in shape.
        DegenerateGeometryError: a bearing is not a finite unit vector, or the
            odometry puts the two optical centres less than 1 cm apart.
    """
    fn = check_bearings("bearings_next", bearings_next)
    fo = check_bearings("bearings_other", bearings_other, len(fn))
    idx = np.asarray(feature_idx_next, dtype=np.int64)
    if idx.shape != (len(fn),):
        raise ShapeError(f"feature_idx_next: expected shape ({len(fn)},), got {idx.shape}")
    t_odom = camera_baseline_level(odom_next, odom_other, mount)
    baseline = float(np.linalg.norm(t_odom))
    if baseline < _MIN_BASELINE_M:
        raise DegenerateGeometryError(
            f"key images {baseline:.4f} m apart by odometry (need >= {_MIN_BASELINE_M} m)"
        )
    fit = relative_pose(fo, fn, rng, config.relative_pose)
    disagreement = math.acos(float(np.clip(fit.t_b_a @ t_odom / baseline, -1.0, 1.0)))
    t_n_o = baseline * fit.t_b_a
    inl = fit.inlier_mask
    tri = triangulate_bearings(fit.R_b_a, t_n_o, fo[inl], fn[inl])
    with np.errstate(invalid="ignore"):
        keep = (tri.in_front & (tri.depths.parallax_rad >= math.radians(config.min_parallax_deg))
                & (np.linalg.norm(tri.points_b, axis=1) <= config.max_point_distance_m))
    feature_idx, first = np.unique(idx[inl][keep], return_index=True)
    points = tri.points_b[keep][first]
    ok = (fit.ok and disagreement <= math.radians(config.max_odometry_disagreement_deg)
          and len(feature_idx) >= config.min_points)
    return KeyPairGeometry(
        points_n=points, feature_idx=feature_idx, R_n_o=fit.R_b_a, t_n_o=t_n_o,
        baseline_m=baseline, fit=fit, odometry_disagreement_rad=disagreement, ok=bool(ok),
    )
