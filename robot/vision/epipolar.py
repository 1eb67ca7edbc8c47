"""Robust relative pose of two views from unit bearings, rays beyond 90 degrees included.

Why not ``cv2.findEssentialMat``: it takes pinhole coordinates x/z, which fold a
ray beyond 90 degrees onto its antipode and measure errors on the z = 1 plane
(reference visual-navigation.md, sec. 4.1). Here everything stays on the sphere:

1. Minimal solvers from PoseLib on bearings: ``relpose_upright_planar_2pt``
   (rotation about y, t_y = 0: the motion of a level camera on a flat floor,
   see :mod:`shared.camera_mount`) and ``relpose_5pt`` (general motion). PoseLib's
   convention is ``X_2 = R X_1 + t``, its cheirality test runs along the rays.
2. MSAC (Torr & Zisserman 2000): hypotheses are scored in batches by the
   truncated squared angular Sampson error; adaptive stopping (Fischler &
   Bolles 1981) at ``config.confidence``.
3. The sign of t (and for 5-point the twisted pair) is chosen by the majority of
   inliers triangulating in front of both cameras (Hartley & Zisserman, sec. 9.6.3);
   inliers that triangulate clearly behind a camera are dropped.
4. Refinement on the inliers: Levenberg-Marquardt with a Huber loss
   (:mod:`robot.vision._robust_lm`) over (yaw, heading of t) for the planar model
   or (rotation vector, t on the sphere) for the general one, starting from the
   inliers at 3x the threshold; inliers are then re-selected and the refinement
   repeated (``config.refine_passes`` in all).

The error is the angular Sampson error on the sphere
(:mod:`robot.vision._epipolar_error`), in radians. Model "auto" runs the planar
model and, when its inlier ratio is below ``config.min_planar_inlier_ratio``
(ramps, a tilted camera, bad matches), the 5-point model as well, keeping the
fit with more inliers (reference sec. 4.4).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import poselib

from robot.config import RelativePoseConfig
from robot.vision._epipolar_error import (
    EpipolarPairs,
    essentials,
    rotation_y,
    rotation_y_derivative,
)
from robot.vision._robust_lm import minimise_huber
from robot.vision.triangulation import ray_depths_unchecked, skew
from shared.errors import DegenerateGeometryError, check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
Bearings = npt.NDArray[np.float64]
"""(N, 3) float64 unit rows: directions of rays from a camera centre, in that camera's frame."""

#: Minimal samples drawn per batch before the stopping test.
_BATCH = 32
#: Inliers whose rays meet behind a camera are dropped when their parallax exceeds this many
#: inlier thresholds (below it the depth sign is noise).
_CHEIRALITY_PARALLAX = 2.0
#: Bearings whose norm is further than this from 1 are refused.
_UNIT_TOLERANCE = 1e-6
#: The first refinement starts from the inliers at this many times the threshold (the
#: local optimisation of LO-RANSAC, Chum, Matas & Kittler 2003): a hypothesis from a noisy
#: minimal sample otherwise locks the refinement onto its own inliers. Measured on a
#: corridor scene with 0.25 m of baseline: direction errors > 5 degrees in 26 of 300 runs
#: with one pass at 1x, 1 of 300 at 2x, 0 of 300 with two passes at 3x.
_FIRST_PASS_WIDEN = 3.0
#: Forward-difference step of the general model's parameters (rad).
_DIFF_STEP = 1e-7

Solver = Callable[[FloatArray, FloatArray], list]


@dataclass(frozen=True, eq=False)
class EpipolarFit:
    """A relative pose of view a with respect to view b, from bearings.

    ``X_b = R_b_a X_a + t_b_a`` maps points from frame a into frame b, so view a's
    centre is at ``t_b_a`` (unit length: the scale is unknown) in frame b.

    Attributes:
        R_b_a: (3, 3) float64 rotation, frame a -> frame b.
        t_b_a: (3,) float64 unit direction of view a's centre seen from b (zeros if no model).
        inlier_mask: (N,) bool, correspondences consistent with the pose.
        residual_rad: (N,) float64 angular Sampson errors under the pose (inf if no model).
        ok: at least ``min_inliers`` inliers.
        model: "planar", "general" or "none" (no hypothesis at all).
        parallax_rad: median angle between the inliers' rays once rotated into one
            frame; near 0 the views barely translated and ``t_b_a`` is unreliable.
    """

    R_b_a: FloatArray
    t_b_a: FloatArray
    inlier_mask: BoolArray
    residual_rad: FloatArray
    ok: bool
    model: str
    parallax_rad: float

    @property
    def n_inliers(self) -> int:
        """Number of inliers."""
        return int(np.count_nonzero(self.inlier_mask))


def check_bearings(name: str, bearings: npt.ArrayLike, n: int | None = None) -> FloatArray:
    """Return ``bearings`` as float64 after checking shape (N, 3), finiteness and unit norm.

    Args:
        name: the argument's name, for messages.
        bearings: the array to check.
        n: the number of rows required, or None for any.

    Raises:
        ShapeError: not (N, 3) (or not n rows).
        DegenerateGeometryError: a row is not finite or not of unit length.
    """
    b = np.asarray(bearings, dtype=np.float64)
    check_shape(name, b.shape, (n, 3))
    norm = np.sqrt(np.einsum("ij,ij->i", b, b))
    bad = ~(np.abs(norm - 1.0) <= _UNIT_TOLERANCE)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise DegenerateGeometryError(
            f"{name}: row {i} is not a finite unit vector ({b[i].tolist()}, norm {norm[i]:.6g})"
        )
    return b


def epipolar_residuals_rad(
    R_b_a: FloatArray, t_b_a: FloatArray, bearings_a: Bearings, bearings_b: Bearings
) -> FloatArray:
    """Signed angular Sampson errors of correspondences under a relative pose.

    Args:
        R_b_a: (3, 3) rotation, frame a -> frame b.
        t_b_a: (3,) direction of a's centre in frame b (its length does not matter).
        bearings_a: (N, 3) unit rays in frame a.
        bearings_b: (N, 3) unit rays in frame b.

    Returns:
        (N,) float64 errors, rad (:mod:`robot.vision._epipolar_error`).

    Raises:
        ShapeError: an argument has the wrong shape.
    """
    check_shape("R_b_a", np.shape(R_b_a), (3, 3))
    check_shape("t_b_a", np.shape(t_b_a), (3,))
    check_shape("bearings_a", np.shape(bearings_a), (None, 3))
    check_shape("bearings_b", np.shape(bearings_b), (len(bearings_a), 3))
    E = essentials(np.asarray(R_b_a, dtype=np.float64)[None],
                   np.asarray(t_b_a, dtype=np.float64)[None])
    pairs = EpipolarPairs(np.asarray(bearings_a, np.float64), np.asarray(bearings_b, np.float64))
    return pairs.errors(E)[0]


def _draw_samples(rng: np.random.Generator, n: int, size: int, count: int) -> npt.NDArray[np.intp]:
    """(count, size) index samples, distinct within each row."""
    samples = rng.integers(0, n, (count, size))
    while True:
        s = np.sort(samples, axis=1)
        dup = np.any(s[:, 1:] == s[:, :-1], axis=1)
        if not np.any(dup):
            return samples
        samples[dup] = rng.integers(0, n, (int(np.count_nonzero(dup)), size))


def _iterations_needed(inlier_ratio: float, size: int, confidence: float) -> float:
    """RANSAC sample count for an all-inlier sample with probability ``confidence``."""
    p_good = inlier_ratio**size
    if p_good >= 1.0:
        return 1.0
    if p_good <= 0.0:
        return math.inf
    return math.log(1.0 - confidence) / math.log(1.0 - p_good)


def _msac(
    fa: FloatArray, fb: FloatArray, pairs: EpipolarPairs, rng: np.random.Generator,
    solver: Solver, size: int, max_iterations: int, config: RelativePoseConfig,
) -> tuple[FloatArray, FloatArray] | None:
    """Best (R, t) by truncated squared error over minimal-sample hypotheses, or None."""
    n = len(fa)
    thr2 = config.inlier_threshold_rad**2
    best: tuple[FloatArray, FloatArray] | None = None
    best_cost = math.inf
    needed: float = max_iterations
    drawn = 0
    while drawn < min(needed, max_iterations):
        count = min(_BATCH, max_iterations - drawn)
        drawn += count
        poses = [p for s in _draw_samples(rng, n, size, count) for p in solver(fa[s], fb[s])]
        if not poses:
            continue
        Rs = np.array([p.R for p in poses])
        ts = np.array([p.t for p in poses])
        norms = np.linalg.norm(ts, axis=1)
        keep = norms > 1e-12
        if not np.any(keep):
            continue
        Rs, ts = Rs[keep], ts[keep] / norms[keep, None]
        r2 = pairs.errors(essentials(Rs, ts)) ** 2
        costs = np.minimum(r2, thr2).sum(axis=1)
        h = int(np.argmin(costs))
        if costs[h] < best_cost:
            best_cost = float(costs[h])
            best = (Rs[h], ts[h])
            ratio = float(np.count_nonzero(r2[h] < thr2)) / n
            needed = _iterations_needed(ratio, size, config.confidence)
    return best


def rotation_from_rotvec(w: FloatArray) -> FloatArray:
    """Rodrigues' formula: (3,) rotation vector, rad -> (3, 3) rotation matrix."""
    theta = float(np.linalg.norm(w))
    K = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    if theta < 1e-12:
        return np.eye(3) + K
    return np.eye(3) + math.sin(theta) / theta * K + (1.0 - math.cos(theta)) / theta**2 * (K @ K)


def _tangent_basis(t: FloatArray) -> FloatArray:
    """(3, 2) orthonormal basis of the plane orthogonal to unit ``t``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(t, helper)
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(t, u)])


def _refine_planar(R: FloatArray, t: FloatArray, pairs: EpipolarPairs,
                   k: float) -> tuple[FloatArray, FloatArray]:
    """Refine (yaw about y, heading of t in the x-z plane) with an analytic Jacobian."""

    def pose(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        return rotation_y(x[0]), np.array([math.sin(x[1]), 0.0, math.cos(x[1])])

    def residuals(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        Rx, tx = pose(x)
        dt = np.array([math.cos(x[1]), 0.0, -math.sin(x[1])])
        dEs = np.array([skew(tx) @ rotation_y_derivative(x[0]), skew(dt) @ Rx])
        return pairs.errors_and_derivatives(skew(tx) @ Rx, dEs)

    x0 = np.array([math.atan2(R[0, 2], R[0, 0]), math.atan2(t[0], t[2])])
    return pose(minimise_huber(residuals, x0, k))


def _refine_general(R: FloatArray, t: FloatArray, pairs: EpipolarPairs,
                    k: float) -> tuple[FloatArray, FloatArray]:
    """Refine (rotation vector applied to R, t on its tangent plane); dE by forward differences."""
    B = _tangent_basis(t)

    def pose(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        tx = t + B @ x[3:]
        return rotation_from_rotvec(x[:3]) @ R, tx / np.linalg.norm(tx)

    def essential(x: FloatArray) -> FloatArray:
        Rx, tx = pose(x)
        return skew(tx) @ Rx

    def residuals(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        E = essential(x)
        dEs = np.array([(essential(x + _DIFF_STEP * e) - E) / _DIFF_STEP for e in np.eye(5)])
        return pairs.errors_and_derivatives(E, dEs)

    return pose(minimise_huber(residuals, np.zeros(5), k))


def _choose_decomposition(R: FloatArray, t: FloatArray, fa: FloatArray, fb: FloatArray,
                          planar: bool, min_parallax: float) -> tuple[FloatArray, FloatArray]:
    """The (R, t) of the same essential matrix with most points in front of both cameras.

    Flipping t flips both depths, so one depth computation per rotation serves both
    signs; the twisted pair (R rotated by pi about t) is not planar and is tried only
    for the general model.
    """
    best, best_votes = (R, t), -1
    rotations = [R] if planar else [R, (2.0 * np.outer(t, t) - np.eye(3)) @ R]
    for Rc in rotations:
        d = ray_depths_unchecked(Rc, t, fa, fb)
        decisive = d.parallax_rad > min_parallax
        with np.errstate(invalid="ignore"):
            front = int(np.count_nonzero(decisive & (d.depth_a > 0) & (d.depth_b > 0)))
            behind = int(np.count_nonzero(decisive & (d.depth_a < 0) & (d.depth_b < 0)))
        for votes, tc in ((front, t), (behind, -t)):
            if votes > best_votes:
                best, best_votes = (Rc, tc), votes
    return best


def _inliers(R: FloatArray, t: FloatArray, fa: FloatArray, fb: FloatArray,
             pairs: EpipolarPairs, config: RelativePoseConfig, widen: float = 1.0
             ) -> tuple[BoolArray, FloatArray, FloatArray]:
    """Inlier mask (threshold times ``widen``), signed residuals and parallax angles (N,)."""
    residual = pairs.errors(essentials(R[None], t[None]))[0]
    d = ray_depths_unchecked(R, t, fa, fb)
    decisive = d.parallax_rad > _CHEIRALITY_PARALLAX * config.inlier_threshold_rad
    with np.errstate(invalid="ignore"):
        front = (d.depth_a > 0) & (d.depth_b > 0)
    inliers = (np.abs(residual) < widen * config.inlier_threshold_rad) & (front | ~decisive)
    return inliers, residual, d.parallax_rad


def _fit_model(fa: FloatArray, fb: FloatArray, pairs: EpipolarPairs, rng: np.random.Generator,
               config: RelativePoseConfig, planar: bool) -> EpipolarFit:
    n = len(fa)
    size = 2 if planar else 5
    none = EpipolarFit(R_b_a=np.eye(3), t_b_a=np.zeros(3), inlier_mask=np.zeros(n, dtype=bool),
                       residual_rad=np.full(n, np.inf), ok=False, model="none", parallax_rad=0.0)
    if n < size:
        return none
    solver: Solver = poselib.relpose_upright_planar_2pt if planar else poselib.relpose_5pt
    max_iterations = config.max_iterations if planar else config.max_iterations_general
    best = _msac(fa, fb, pairs, rng, solver, size, max_iterations, config)
    if best is None:
        return none
    R, t = best
    refine = _refine_planar if planar else _refine_general
    inliers = np.abs(pairs.errors(essentials(R[None], t[None]))[0]) < config.inlier_threshold_rad
    R, t = _choose_decomposition(R, t, fa[inliers], fb[inliers], planar,
                                 _CHEIRALITY_PARALLAX * config.inlier_threshold_rad)
    widen = _FIRST_PASS_WIDEN if config.refine_passes else 1.0
    inliers, residual, parallax = _inliers(R, t, fa, fb, pairs, config, widen)
    for _ in range(config.refine_passes):
        if np.count_nonzero(inliers) >= size:
            R, t = refine(R, t, pairs.subset(inliers), config.huber_scale_rad)
        inliers, residual, parallax = _inliers(R, t, fa, fb, pairs, config)
    return EpipolarFit(
        R_b_a=R, t_b_a=t, inlier_mask=inliers, residual_rad=residual,
        ok=bool(np.count_nonzero(inliers) >= config.min_inliers),
        model="planar" if planar else "general",
        parallax_rad=float(np.median(parallax[inliers])) if np.any(inliers) else 0.0,
    )


def relative_pose(
    bearings_a: Bearings, bearings_b: Bearings, rng: np.random.Generator,
    config: RelativePoseConfig,
) -> EpipolarFit:
    """Robust relative pose of view a with respect to view b from matched unit bearings.

    Args:
        bearings_a: (N, 3) unit rays of the matches in view a's frame; for the
            planar model, a level frame (y vertical, see :mod:`shared.camera_mount`).
        bearings_b: (N, 3) unit rays of the same matches in view b's frame.
        rng: draws the minimal samples.
        config: model, thresholds and iteration limits.

    Returns:
        The fit; ``ok`` is False (an expected outcome) when there are too few
        matches or too few inliers.

    Raises:
        ShapeError: the arrays are not (N, 3) with equal N.
        DegenerateGeometryError: a bearing is not a finite unit vector.
    """
    fa = check_bearings("bearings_a", bearings_a)
    fb = check_bearings("bearings_b", bearings_b, len(fa))
    pairs = EpipolarPairs(fa, fb)
    if config.model == "general":
        return _fit_model(fa, fb, pairs, rng, config, planar=False)
    fit = _fit_model(fa, fb, pairs, rng, config, planar=True)
    if config.model == "planar" or fit.n_inliers >= config.min_planar_inlier_ratio * len(fa):
        return fit
    general = _fit_model(fa, fb, pairs, rng, config, planar=False)
    return general if general.n_inliers > fit.n_inliers else fit
