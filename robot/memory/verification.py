"""Geometric verification: is a key image the same place as the query, or a chance look-alike?

The paper (Courbon et al. 2008, sec. II-D) ranks key images by their number of
matches. On real images that count cannot tell places apart: two unrelated views
share a median 30 chance matches (issue 16), as many as a true pair seen from a
little aside. Place recognition verifies geometrically instead (Philbin et al.,
CVPR 2007, spatial re-ranking; Cummins and Newman, FAB-MAP, IJRR 2008, sec. 6; the
teach-and-repeat systems of Furgale and Barfoot, JFR 2010, accept a match only
through a robustly fitted relative pose):

1. The matches are lifted to unit bearings in the *level* camera frame of the
   mount (:func:`robot.vision.bearings.level_bearings`: y vertical, so the camera's
   own pitch and roll on the robot are taken out).
2. A relative pose is fitted to them (:func:`robot.vision.epipolar.relative_pose`,
   inlier tolerance an angle on the sphere, so the test means the same on any lens).
   When it finds too few inliers, a pure rotation is fitted too (:func:`rotation_only`):
   a query taken where the key image was has no baseline, and the essential matrix is
   then undetermined; the model with more inliers is tested.
3. The key image is *accepted* when all of these hold:

   * enough inliers (``min_inliers``): a minimal 5-point sample explains a few
     chance matches by construction;
   * a large enough share of the matches are inliers (``min_inlier_ratio``): chance
     matches are spread evenly, true ones agree with one motion;
   * the motion is one a ground robot can make between two visits of a place: the
     rotation about the vertical axis is at most ``max_yaw_deg`` and the vertical
     axis tilts by at most ``max_tilt_deg`` (the floor is flat to within a ramp; a
     fit that needs the camera rolled over is explaining noise).

This module is a pure core: bearings and a config in, a :class:`Verification` out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robot.config import LocalizeConfig, RelativePoseConfig
from robot.vision.epipolar import Bearings, EpipolarFit, relative_pose
from shared.errors import check_shape

_ROTATION_SAMPLES = 64
"""2-point samples of :func:`rotation_only`: an all-inlier one with probability 0.9996
at the lowest inlier ratio accepted, 0.35 (1 - (1 - 0.35^2)^64)."""

_NO_TRANSLATION = 1e-9
"""A fitted translation shorter than this on the level plane has no direction there."""

#: Why a candidate was refused, in the order the tests are applied (``accepted`` when none).
ACCEPTED = "accepted"
TOO_FEW_MATCHES = "too few matches"
TOO_FEW_INLIERS = "too few inliers"
LOW_INLIER_RATIO = "inlier ratio too low"
TOO_MUCH_YAW = "turned too far"
TOO_MUCH_TILT = "tilted too far"


@dataclass(frozen=True, slots=True)
class Verification:
    """The geometric verification of one query / key image pair.

    Attributes:
        matches: matches whose two pixels lift to valid bearings.
        inliers: matches consistent with the fitted relative pose (0 when not fitted).
        inlier_ratio: ``inliers / matches`` (0.0 when there are no matches).
        yaw_deg: rotation of the query's level frame about the vertical axis to the
            key image's, degrees in (-180, 180] (nan when not fitted).
        tilt_deg: angle between the two level frames' vertical axes, degrees in
            [0, 180] (nan when not fitted).
        verdict: :data:`ACCEPTED` or the first test that failed.
        along: where the query's centre lies from the key image's on the level plane:
            the cosine of its direction from the key image's forward axis, in [-1, 1]
            (> 0 ahead of the key image, < 0 behind; the scale is unknown, the side
            is not); nan when the fit has no translation (a pure rotation, or no fit).
    """

    matches: int
    inliers: int
    inlier_ratio: float
    yaw_deg: float
    tilt_deg: float
    verdict: str
    along: float = math.nan

    @property
    def accepted(self) -> bool:
        """Whether the pair passed every test: the key image is the query's place."""
        return self.verdict == ACCEPTED


def verify_bearings(
    bearings_query: Bearings,
    bearings_key: Bearings,
    rng: np.random.Generator,
    config: LocalizeConfig,
) -> Verification:
    """Fit a relative pose to matched bearings and apply the acceptance tests.

    Args:
        bearings_query: (N, 3) float64 unit rows, the matches in the query's level frame.
        bearings_key: (N, 3) float64 unit rows, the same matches in the key image's
            level frame.
        rng: draws RANSAC's samples.
        config: the tests' thresholds and the relative pose's configuration.

    Returns:
        The verification (refused pairs are results, not errors).

    Raises:
        ShapeError: the arrays are not (N, 3) with equal N.
        DegenerateGeometryError: a bearing is not a finite unit vector.
    """
    check_shape("bearings_query", np.shape(bearings_query), (None, 3))
    check_shape("bearings_key", np.shape(bearings_key), (len(bearings_query), 3))
    n = len(bearings_query)
    if n < config.min_inliers:
        return Verification(n, 0, 0.0, math.nan, math.nan, TOO_FEW_MATCHES)
    fit = relative_pose(bearings_query, bearings_key, rng, config.relative_pose)
    verification = verdict_of_fit(fit, n, config)
    if verification.verdict in (TOO_FEW_INLIERS, LOW_INLIER_RATIO):
        rotation = rotation_only(bearings_query, bearings_key, rng, config.relative_pose)
        if rotation.n_inliers > fit.n_inliers:
            return verdict_of_fit(rotation, n, config)
    return verification


def rotation_only(bearings_a: Bearings, bearings_b: Bearings, rng: np.random.Generator,
                  config: RelativePoseConfig) -> EpipolarFit:
    """A pure rotation ``b = R_b_a a`` fitted to matched bearings (2-point RANSAC, Kabsch).

    A query taken where its key image was (no baseline: the best case of localization)
    leaves the essential matrix undetermined, and the 5-point fit finds few inliers;
    the rotation explains such a pair. Inliers are within ``inlier_threshold_rad``
    of their rotated bearing.

    Args:
        bearings_a, bearings_b: (N, 3) float64 unit rows, N >= 2.
        rng: draws the samples.
        config: the inlier tolerance.

    Returns:
        The fit (``model`` "rotation", ``t_b_a`` zeros, ``parallax_rad`` 0).
    """
    a, b = np.asarray(bearings_a, np.float64), np.asarray(bearings_b, np.float64)
    best = np.zeros(len(a), bool)
    best_R = np.eye(3)
    for _ in range(_ROTATION_SAMPLES):
        pair = rng.choice(len(a), 2, replace=False)
        R = _kabsch(a[pair], b[pair])
        inliers = _angles(R, a, b) < config.inlier_threshold_rad
        if inliers.sum() > best.sum():
            best, best_R = inliers, R
    if best.sum() >= 3:
        best_R = _kabsch(a[best], b[best])
    residual = _angles(best_R, a, b)
    inliers = residual < config.inlier_threshold_rad
    return EpipolarFit(best_R, np.zeros(3), inliers, residual,
                       bool(inliers.sum() >= config.min_inliers), "rotation", 0.0)


def _kabsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation R (3, 3) minimising sum |b_i - R a_i|^2 over rows a_i, b_i."""
    u, _, vt = np.linalg.svd(b.T @ a)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


def _angles(R: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N,) angles between ``R a_i`` and ``b_i``, rad."""
    return np.arccos(np.clip(np.einsum("ij,ij->i", a @ R.T, b), -1.0, 1.0))


def verdict_of_fit(fit: EpipolarFit, matches: int, config: LocalizeConfig) -> Verification:
    """Apply the acceptance tests to a fitted relative pose of ``matches`` correspondences.

    Args:
        fit: the pose of the query's level frame (a) relative to the key image's (b).
        matches: the number of correspondences it was fitted to.
        config: the thresholds.
    """
    inliers = fit.n_inliers
    ratio = inliers / matches if matches else 0.0
    yaw_deg, tilt_deg = yaw_tilt_deg(fit.R_b_a)
    if inliers < config.min_inliers:
        verdict = TOO_FEW_INLIERS
    elif ratio < config.min_inlier_ratio:
        verdict = LOW_INLIER_RATIO
    elif abs(yaw_deg) > config.max_yaw_deg:
        verdict = TOO_MUCH_YAW
    elif tilt_deg > config.max_tilt_deg:
        verdict = TOO_MUCH_TILT
    else:
        verdict = ACCEPTED
    t = fit.t_b_a  # the query's centre seen from the key image, level frame (z forward)
    level = math.hypot(float(t[0]), float(t[2]))
    along = float(t[2]) / level if level > _NO_TRANSLATION else math.nan
    return Verification(matches, inliers, ratio, yaw_deg, tilt_deg, verdict, along)


def yaw_tilt_deg(R_b_a: np.ndarray) -> tuple[float, float]:
    """The turn about the vertical and the tilt of a rotation between two level frames.

    Level frames are x right, y down (vertical), z forward
    (:mod:`shared.camera_mount`). The tilt is the angle between the vertical axis
    of frame a seen in frame b, ``R_b_a @ (0, 1, 0)``, and b's own; the yaw is
    the heading of a's forward axis seen in b, ``R_b_a @ (0, 0, 1)``, in b's
    horizontal x-z plane, positive towards +x (a turn to the right about y down).

    Args:
        R_b_a: (3, 3) rotation, frame a -> frame b.

    Returns:
        (yaw, tilt), degrees: yaw in (-180, 180], tilt in [0, 180].
    """
    check_shape("R_b_a", np.shape(R_b_a), (3, 3))
    tilt = math.degrees(math.acos(float(np.clip(R_b_a[1, 1], -1.0, 1.0))))
    yaw = math.degrees(math.atan2(float(R_b_a[0, 2]), float(R_b_a[2, 2])))
    return yaw, tilt
