"""Metric planar pose of the current view from key-pair points and epipolar matches.

Reference visual-navigation.md, sec. 1.2, steps 3-4, restricted to the robot's
three degrees of freedom: the current level camera differs from the next key
image's by a yaw phi about the (vertical) y axis and an optical centre C = (c_x,
0, c_z), so ``X_n = R_y(phi) X_c + C``. Two kinds of measurement constrain it:

* key-pair points X_n (metric, :mod:`robot.vision.key_pair`) seen along b_c in
  the current view: the chord residual ``X_c / |X_c| - b_c`` with ``X_c = R^T
  (X_n - C)`` (three components, length 2 sin(angle / 2), so no antipodal
  ambiguity beyond 90 degrees); these fix the scale;
* every epipolar inlier between the current and next views: the angular Sampson
  error (:mod:`robot.vision._epipolar_error`) with t = C / |C|, scale-free, which
  sharpens the yaw and the direction of C.

The start comes from the two-view fit: its yaw, and C = lambda t with lambda the
median over the points of the least-squares distance along t that puts X_n on the
ray R b_c (``u x X_n = lambda u x t``, u = R b_c). Then Levenberg-Marquardt with
a Huber loss and analytic Jacobians on the fit's inliers, re-selection of the
point and epipolar inliers among all matches, and a second pass.

A second start comes from the points alone (:func:`_start_from_points`): where every
point is far, the two-view fit can trade a sideways shift for a turn (measured in the
``campus`` courtyard, points 8-13 m away: translation directions 35-90 degrees off with
yaws 2-4 degrees off, and the refinement then stayed in that basin, |y| errors up to
58 cm). For yaws within 10 degrees of the fit's, each pair of points gives the centre
by linear least squares; when the best hypothesis has more points within
``point_threshold_rad`` than the first result and, unrefined, a truncated (MSAC) cost
over all points and matches below 1.25 times the refined first result's, it is refined
as well (from its own inliers), and the result with the lower cost is kept (the test
spares the second refinement in about two frames of three).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import numpy as np
import numpy.typing as npt

from robot.config import PathStateConfig
from robot.vision._epipolar_error import EpipolarPairs, rotation_y, rotation_y_derivative
from robot.vision._robust_lm import minimise_huber
from robot.vision.epipolar import check_bearings
from robot.vision.triangulation import cross_rows, skew
from shared.errors import check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Points whose ray is within this angle of the translation direction carry no scale.
_MIN_SCALE_ANGLE_RAD = math.radians(1.0)
#: |C| below this is treated as zero when forming t = C / |C|, m.
_MIN_CENTRE_M = 1e-9
#: Point pairs tried for the start from the points alone (:func:`_centre_from_points`).
_CENTRE_SAMPLES = 200
#: Yaws tried around the two-view fit's by :func:`_start_from_points`, rad.
_YAW_SEARCH_DEG = 10.0
_YAW_GRID_RAD = np.radians(np.arange(-_YAW_SEARCH_DEG, _YAW_SEARCH_DEG + 0.5, 1.0))
#: The start from the points is refined when, unrefined, its truncated cost is below this
#: times the refined first result's (a refinement lowers the cost by a few percent to a
#: third: 34.6 -> 33.5, 45.5 -> 38.2 on campus frames).
_SECOND_START_COST_RATIO = 1.25
#: Points nearer than this count as this far when their equations are weighted, m.
_MIN_POINT_DISTANCE_M = 0.1
#: Refinements, each followed by re-selecting the inliers among all matches.
_PASSES = 2


@dataclass(frozen=True, eq=False)
class PlanarResection:
    """The current level camera's metric pose in the next key image's level frame.

    Attributes:
        T_n_c: (4, 4) float64, ``X_n = T_n_c X_c`` (rotation about y, centre at y = 0), m.
        point_inlier_mask: (K,) bool, matches whose key-pair point lies within
            ``config.point_threshold_rad`` of the current ray.
        point_residual_rad: (K,) float64 angle between each match's point and its ray,
            rad (NaN where the match has no point).
        epipolar_inlier_mask: (K,) bool, matches within the epipolar inlier threshold.
        ok: at least ``config.min_points`` point inliers.
    """

    T_n_c: FloatArray
    point_inlier_mask: BoolArray
    point_residual_rad: FloatArray
    epipolar_inlier_mask: BoolArray
    ok: bool

    @property
    def n_point_inliers(self) -> int:
        """Number of point inliers."""
        return int(np.count_nonzero(self.point_inlier_mask))


def _initial_scale(u: FloatArray, points_n: FloatArray, t: FloatArray) -> float:
    """Median over points of the distance along unit t that puts each point on its ray u."""
    ut = u @ skew(t)  # u x t (rows)
    ux = cross_rows(u, points_n)
    nn = np.einsum("ij,ij->i", ut, ut)
    usable = nn > math.sin(_MIN_SCALE_ANGLE_RAD) ** 2
    if not np.any(usable):
        return 0.0
    return float(np.median(np.einsum("ij,ij->i", ux[usable], ut[usable]) / nn[usable]))


def _residuals(x: FloatArray, bp: FloatArray, points_n: FloatArray,
               pairs: EpipolarPairs) -> tuple[FloatArray, FloatArray]:
    """Residuals (3P chord components, component-major, then K Sampson errors) and Jacobian.

    With D = X_n - C, X_c = R_y(phi)^T D = (c D_x - s D_z, D_y, s D_x + c D_z) and
    h = X_c / |X_c|: d h / d phi = (-h_z, 0, h_x) (a rotation about y moves h
    perpendicular to itself), and for a unit change of C along u (u = -R^T e_x or
    -R^T e_z in the current frame), d h = (u - h (h . u)) / |X_c|.
    """
    c, s = math.cos(x[0]), math.sin(x[0])
    dx, dy, dz = points_n[:, 0] - x[1], points_n[:, 1], points_n[:, 2] - x[2]
    px, py, pz = c * dx - s * dz, dy, s * dx + c * dz
    inv = 1.0 / np.sqrt(px * px + py * py + pz * pz)
    hx, hy, hz = px * inv, py * inv, pz * inv
    zeros = np.zeros_like(hx)
    columns = [np.concatenate([-hz, zeros, hx])]
    for ux, uz in ((-c, -s), (s, -c)):  # d X_c / d c_x and d X_c / d c_z
        k = hx * ux + hz * uz
        columns.append(np.concatenate([(ux - hx * k) * inv, -hy * k * inv, (uz - hz * k) * inv]))
    R = rotation_y(x[0])
    centre = math.hypot(x[1], x[2])
    if centre > _MIN_CENTRE_M:
        t = np.array([x[1], 0.0, x[2]]) / centre
        dts = ((np.array([1.0, 0.0, 0.0]) - t * t[0]) / centre,
               (np.array([0.0, 0.0, 1.0]) - t * t[2]) / centre)
    else:
        # At the key image itself every direction fits the (pure rotation) matches.
        t, dts = np.array([0.0, 0.0, 1.0]), (np.zeros(3), np.zeros(3))
    dR = rotation_y_derivative(x[0])
    r_epi, J_epi = pairs.errors_and_derivatives(
        skew(t) @ R, np.array([skew(t) @ dR, skew(dts[0]) @ R, skew(dts[1]) @ R])
    )
    r_points = np.concatenate([hx - bp[:, 0], hy - bp[:, 1], hz - bp[:, 2]])
    return np.concatenate([r_points, r_epi]), np.vstack([np.column_stack(columns), J_epi])


def _pose_matrix(x: FloatArray) -> FloatArray:
    T = np.eye(4)
    T[:3, :3] = rotation_y(x[0])
    T[:3, 3] = (x[1], 0.0, x[2])
    return T


def _start_from_points(bp: FloatArray, Xp: FloatArray, yaw0: float,
                       threshold_rad: float) -> tuple[FloatArray, int] | None:
    """A pose (yaw, c_x, c_z) that the most key-pair points agree with, found without the
    two-view fit's direction.

    For a yaw, u = R_y(yaw) b_c and a point X_n on its ray means u x (X_n - C) = 0: two
    independent linear equations in C = (c_x, 0, c_z), divided by the point's distance so
    that they measure angles. Every pair of points (up to :data:`_CENTRE_SAMPLES`) gives a
    centre by least squares, for each yaw of a grid around ``yaw0``
    (:data:`_YAW_SEARCH_DEG`): far points let a sideways shift pass for a turn, so the
    two-view yaw is not trusted to better than a few degrees. The hypothesis with the most
    points within ``threshold_rad`` is returned. None with fewer than two points.
    """
    n = len(Xp)
    if n < 2:
        return None
    w = 1.0 / np.maximum(np.linalg.norm(Xp, axis=1), _MIN_POINT_DISTANCE_M)
    i, j = np.triu_indices(n, 1)
    if len(i) > _CENTRE_SAMPLES:
        pick = np.linspace(0, len(i) - 1, _CENTRE_SAMPLES).astype(np.intp)
        i, j = i[pick], j[pick]
    yaws = yaw0 + _YAW_GRID_RAD
    c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
    # u = R_y(yaw) b_c for every yaw: (Y, n, 3).
    u = np.stack([c * bp[:, 0] + s * bp[:, 2], np.repeat(bp[None, :, 1], len(yaws), axis=0),
                  -s * bp[:, 0] + c * bp[:, 2]], axis=2)
    ux, uy, uz = u[..., 0] * w, u[..., 1] * w, u[..., 2] * w
    # A_k C = u_k x X_k with A_k = [[0, u_y], [u_z, -u_x], [-u_y, 0]] on (c_x, c_z); the
    # normal equations per point, then per pair of points.
    m00, m01, m11 = uz * uz + uy * uy, -uz * ux, uy * uy + ux * ux
    rhs = np.stack([uy * Xp[:, 2] - uz * Xp[:, 1], uz * Xp[:, 0] - ux * Xp[:, 2],
                    ux * Xp[:, 1] - uy * Xp[:, 0]], axis=2)  # (u x X) w, as the rows of A
    v0, v1 = uz * rhs[..., 1] - uy * rhs[..., 2], uy * rhs[..., 0] - ux * rhs[..., 1]
    a00, a01, a11 = m00[:, i] + m00[:, j], m01[:, i] + m01[:, j], m11[:, i] + m11[:, j]
    b0, b1 = v0[:, i] + v0[:, j], v1[:, i] + v1[:, j]
    det = a00 * a11 - a01 * a01
    det = np.where(np.abs(det) > 1e-12, det, np.inf)
    cx, cz = (a11 * b0 - a01 * b1) / det, (a00 * b1 - a01 * b0) / det  # (Y, m)
    # Each point's ray from each centre against its bearing: (Y, m, n).
    dx = Xp[None, None, :, 0] - cx[..., None]
    dz = Xp[None, None, :, 2] - cz[..., None]
    dy = np.broadcast_to(Xp[None, None, :, 1], dx.shape)
    dot = (dx * u[:, None, :, 0] + dy * u[:, None, :, 1] + dz * u[:, None, :, 2])
    cos_min = math.cos(threshold_rad)
    votes = (dot > cos_min * np.sqrt(dx * dx + dy * dy + dz * dz)).sum(axis=2)
    y, h = np.unravel_index(int(np.argmax(votes)), votes.shape)
    if votes[y, h] < 2:
        return None
    return np.array([yaws[y], cx[y, h], cz[y, h]]), int(votes[y, h])


def _refine(x: FloatArray, bp: FloatArray, Xp: FloatArray, pairs: EpipolarPairs,
            use_p: BoolArray, use_e: BoolArray, config: PathStateConfig
            ) -> tuple[FloatArray, BoolArray, BoolArray, FloatArray, float]:
    """The passes of LM from ``x`` with inlier re-selection; then the truncated (MSAC) cost
    over all points and matches, each term in units of its threshold squared."""
    k = config.pose_before_resection.huber_scale_rad
    point_thr = config.point_threshold_rad
    epi_thr = config.pose_before_resection.inlier_threshold_rad
    point_residual = np.full(len(bp), np.inf)
    for _ in range(_PASSES):
        if 3 * np.count_nonzero(use_p) + np.count_nonzero(use_e) >= 3:
            used = partial(_residuals, bp=bp[use_p], points_n=Xp[use_p],
                           pairs=pairs.subset(use_e))
            x = minimise_huber(used, x, k)
        r, _ = _residuals(x, bp, Xp, pairs)
        chord = np.linalg.norm(r[: 3 * len(bp)].reshape(3, -1), axis=0)
        point_residual = 2.0 * np.arcsin(np.minimum(chord / 2.0, 1.0))
        use_p = point_residual < point_thr
        use_e = np.abs(r[3 * len(bp):]) < epi_thr
    return x, use_p, use_e, point_residual, _truncated_cost(point_residual,
                                                           np.abs(r[3 * len(bp):]), config)


def _truncated_cost(point_residual: FloatArray, epipolar_residual: FloatArray,
                    config: PathStateConfig) -> float:
    """MSAC cost of a pose: each point's and each match's squared residual in units of its
    tolerance, capped at 1."""
    point_thr = config.point_threshold_rad
    epi_thr = config.pose_before_resection.inlier_threshold_rad
    return float(np.sum(np.minimum(point_residual / point_thr, 1.0) ** 2)
                 + np.sum(np.minimum(epipolar_residual / epi_thr, 1.0) ** 2))


def resect_planar(
    bearings_c: FloatArray, bearings_n: FloatArray, points_n: FloatArray,
    initial_inliers: npt.ArrayLike, R_n_c: FloatArray, t_n_c: FloatArray,
    config: PathStateConfig,
) -> PlanarResection:
    """Metric planar pose of the current view with respect to the next key image.

    Args:
        bearings_c: (K, 3) unit rays of the current-next matches, current level frame.
        bearings_n: (K, 3) the same matches in the next key image's level frame.
        points_n: (K, 3) the key-pair point of each match's next-image feature, next
            level frame, m; NaN rows where the feature has none.
        initial_inliers: (K,) bool, the two-view fit's inliers (the first pass uses
            these; later passes re-select among all matches).
        R_n_c: (3, 3) starting rotation (the two-view fit's; its yaw about y is used).
        t_n_c: (3,) starting direction of the current centre in the next's frame.
        config: thresholds (``point_threshold_rad``, ``min_points``, and
            ``pose_before_resection``'s ``inlier_threshold_rad`` and ``huber_scale_rad``).

    Returns:
        The pose; ``ok`` is False (an expected outcome) with too few point inliers.

    Raises:
        ShapeError: the arrays disagree in shape.
        DegenerateGeometryError: a bearing is not a finite unit vector.
    """
    fc = check_bearings("bearings_c", bearings_c)
    fn = check_bearings("bearings_n", bearings_n, len(fc))
    X = np.asarray(points_n, dtype=np.float64)
    check_shape("points_n", X.shape, (len(fc), 3))
    use_e = np.asarray(initial_inliers, dtype=bool)
    check_shape("initial_inliers", use_e.shape, (len(fc),))
    check_shape("R_n_c", np.shape(R_n_c), (3, 3))
    check_shape("t_n_c", np.shape(t_n_c), (3,))
    has_point = np.all(np.isfinite(X), axis=1)
    rows = np.flatnonzero(has_point)
    bp, Xp = fc[rows], X[rows]
    R0 = np.asarray(R_n_c, dtype=np.float64)
    yaw = math.atan2(R0[0, 2], R0[0, 0])
    t0 = np.array([t_n_c[0], 0.0, t_n_c[2]], dtype=np.float64)
    t0 /= max(float(np.linalg.norm(t0)), _MIN_CENTRE_M)
    use_p = use_e[rows]
    if np.count_nonzero(use_p) < config.min_points:
        return PlanarResection(
            T_n_c=np.eye(4), point_inlier_mask=np.zeros(len(fc), dtype=bool),
            point_residual_rad=np.full(len(fc), np.nan), epipolar_inlier_mask=use_e, ok=False,
        )
    scale = _initial_scale(bp[use_p] @ rotation_y(yaw).T, Xp[use_p], t0)
    pairs = EpipolarPairs(fc, fn)
    best = _refine(np.array([yaw, scale * t0[0], scale * t0[2]]), bp, Xp, pairs, use_p, use_e,
                   config)
    from_points = _start_from_points(bp, Xp, yaw, config.point_threshold_rad)
    if from_points is not None and from_points[1] > np.count_nonzero(best[1]):
        x0 = from_points[0]
        r, _ = _residuals(x0, bp, Xp, pairs)
        point_residual = 2.0 * np.arcsin(np.minimum(
            np.linalg.norm(r[: 3 * len(bp)].reshape(3, -1), axis=0) / 2.0, 1.0))
        epi = np.abs(r[3 * len(bp):])
        if _truncated_cost(point_residual, epi, config) < _SECOND_START_COST_RATIO * best[4]:
            # Unrefined, it already explains the points and matches better than the
            # refined first result: a pose the two-view fit did not lead to. Refine it
            # from its own inliers and keep the better of the two.
            other = _refine(x0, bp, Xp, pairs, point_residual < config.point_threshold_rad,
                            epi < config.pose_before_resection.inlier_threshold_rad, config)
            if other[4] < best[4]:
                best = other
    x, use_p, use_e, point_residual, _ = best
    point_inliers = np.zeros(len(fc), dtype=bool)
    point_inliers[rows] = use_p
    residual_all = np.full(len(fc), np.nan)
    residual_all[rows] = point_residual
    return PlanarResection(
        T_n_c=_pose_matrix(x), point_inlier_mask=point_inliers, point_residual_rad=residual_all,
        epipolar_inlier_mask=use_e, ok=bool(np.count_nonzero(use_p) >= config.min_points),
    )
