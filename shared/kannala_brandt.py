"""The equidistant (Kannala-Brandt) fisheye model, and the unified model fitted to it.

Calibration tools other than vmnav's (``cv2.fisheye``, Kalibr's ``pinhole-equi``,
Basalt, Kimera) describe a fisheye lens in the equidistant model of Kannala and
Brandt (IEEE TPAMI 28(8), 2006, eq. 6), as ``cv2.fisheye`` implements it::

    theta   = angle of the ray X_c from the optical axis (atan2(|x, y|, z))
    theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
    u       = fx theta_d cos(phi) + cx,   v = fy theta_d sin(phi) + cy

where phi is the ray's azimuth about the axis. vmnav's camera is Mei's unified model
(:mod:`shared.camera_model`). :func:`fit_unified` converts: both models are radially
symmetric about the principal point, so the unified camera keeps (cx, cy) and the
aspect ratio fy / fx exactly, and only its scale ``g`` (fx_u = g fx), ``xi`` and, when
needed, its radial distortion (k1, k2) are fitted, by least squares on the pixels of a
grid over the image lifted to bearings through the equidistant model (a few hundred
samples: the radial profile is smooth). Tangential distortion (p1, p2) stays 0: the
equidistant model has none.

The fit is variable projection (Golub & Pereyra 1973): for a given xi the unified
radius ``g m (1 + k1 m^2 + k2 m^4)``, ``m = sin(theta) / (cos(theta) + xi)``, is linear
in ``(g, g k1, g k2)``, which one linear least-squares solve gives; only xi is searched
(a grid over [0, :data:`XI_MAX`], then Brent's method), so there is no initial guess to
get wrong and no slow valley to crawl along (xi, k1 and k2 trade off: a general
4-parameter Levenberg-Marquardt took about 120 evaluations). The residual stated is
then measured through :meth:`CameraModel.project` itself, on the same pixels.

An undistorted equidistant lens is xi = 2 in the unified model to third order (the
unified radius is ``g / (1 + xi) theta (1 + (1 / (2 (1 + xi)) - 1/6) theta^2 + ...)``),
so values of 2-3 are what these lenses are, not a degenerate fit. Distortion is added
only when the undistorted fit misses by more than :data:`DISTORTION_ABOVE_PX` somewhere
in the image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.errors import CalibrationError, check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: The undistorted unified model is kept when its largest residual over the image is
#: at most this, px; beyond it (k1, k2) are fitted as well.
DISTORTION_ABOVE_PX = 0.25
#: Grid of pixels sampled over the image for the fit (columns, rows).
FIT_GRID = (32, 20)
#: Bounds of the fitted xi and of |k1|, |k2|.
XI_MAX = 6.0
K_MAX = 1.0
_NEWTON_ITER = 20


@dataclass(frozen=True, eq=False)
class KannalaBrandtCamera:
    """A camera in the equidistant (Kannala-Brandt) model, as ``cv2.fisheye`` has it.

    Attributes:
        width: image width, px.
        height: image height, px.
        fx, fy: focal lengths, px per radian of theta_d.
        cx, cy: principal point, px (OpenCV's convention: the top-left pixel's centre is 0).
        k: (4,) float64 ``(k1, k2, k3, k4)``, dimensionless.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    k: FloatArray = field(default_factory=lambda: np.zeros(4))

    def __post_init__(self) -> None:
        k = np.asarray(self.k, dtype=np.float64).reshape(-1)
        check_shape("k", k.shape, (4,))
        k.setflags(write=False)
        object.__setattr__(self, "k", k)

    def theta_d(self, theta: FloatArray) -> FloatArray:
        """The distorted angle of rays ``theta`` rad off the axis (module docstring), rad."""
        t2 = theta * theta
        k1, k2, k3, k4 = self.k
        return theta * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))

    @property
    def theta_max_rad(self) -> float:
        """Largest angle off the axis up to which the model is one-to-one (theta_d rising),
        rad, at most pi."""
        theta = np.linspace(0.0, math.pi, 3601)
        falling = np.flatnonzero(np.diff(self.theta_d(theta)) <= 0.0)
        return float(theta[falling[0]]) if falling.size else math.pi

    def project(self, points_c: npt.ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Camera-frame directions (N, 3) to pixels (N, 2) and validity (N,) (one-to-one part)."""
        X = np.asarray(points_c, dtype=np.float64)
        check_shape("points_c", X.shape, (None, 3))
        rho = np.hypot(X[:, 0], X[:, 1])
        theta = np.arctan2(rho, X[:, 2])
        phi = np.arctan2(X[:, 1], X[:, 0])
        td = self.theta_d(theta)
        pixels = np.stack([self.fx * td * np.cos(phi) + self.cx,
                           self.fy * td * np.sin(phi) + self.cy], axis=1)
        nonzero = (rho > 0.0) | (X[:, 2] > 0.0)
        return pixels, nonzero & (theta < self.theta_max_rad)

    def lift(self, pixels_xy: npt.ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Pixels (N, 2) to unit bearings (N, 3) in the camera frame and validity (N,).

        theta is found from theta_d by Newton's method; a pixel is invalid where
        theta_d exceeds the model's one-to-one range (:attr:`theta_max_rad`).
        """
        p = np.asarray(pixels_xy, dtype=np.float64)
        check_shape("pixels_xy", p.shape, (None, 2))
        x, y = (p[:, 0] - self.cx) / self.fx, (p[:, 1] - self.cy) / self.fy
        td = np.hypot(x, y)
        theta_max = self.theta_max_rad
        valid = td < self.theta_d(np.array([theta_max]))[0]
        theta = np.minimum(td, theta_max)
        k1, k2, k3, k4 = self.k
        for _ in range(_NEWTON_ITER):
            t2 = theta * theta
            slope = 1.0 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)))
            theta = np.clip(theta - (self.theta_d(theta) - td) / slope, 0.0, theta_max)
        phi = np.arctan2(y, x)
        s = np.sin(theta)
        bearings = np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(theta)], axis=1)
        return bearings, valid


@dataclass(frozen=True, eq=False)
class UnifiedFit:
    """The unified camera fitted to an equidistant one (:func:`fit_unified`).

    Attributes:
        camera: the unified (Mei) camera.
        rms_px: RMS distance over the image between the two models' pixels of the same
            rays, px (on a grid of :data:`FIT_GRID` pixels: what the fit minimised).
        max_px: largest such distance, px.
        with_distortion: whether (k1, k2) were fitted (else D = 0).
        samples: number of pixels sampled.
    """

    camera: CameraModel
    rms_px: float
    max_px: float
    with_distortion: bool
    samples: int


def fit_unified(kb: KannalaBrandtCamera, where: str) -> UnifiedFit:
    """Fit the unified model to an equidistant camera over its image (module docstring).

    Args:
        kb: the equidistant camera.
        where: the calibration it came from, for errors.

    Returns:
        The unified camera, with ``fov_deg`` twice the largest angle off the axis seen
        in the image (rounded up to a degree), and the residual, measured through
        :meth:`CameraModel.project`.

    Raises:
        CalibrationError: a pixel of the image lies beyond the equidistant model's
            one-to-one range, or the fit is not a valid camera.
    """
    from scipy.optimize import minimize_scalar

    u = np.linspace(0.0, kb.width - 1.0, FIT_GRID[0])
    v = np.linspace(0.0, kb.height - 1.0, FIT_GRID[1])
    pixels = np.stack(np.meshgrid(u, v), axis=-1).reshape(-1, 2)
    bearings, valid = kb.lift(pixels)
    if not valid.all():
        bad = pixels[np.argmin(valid)]
        raise CalibrationError(where, f"pixel ({bad[0]:.0f}, {bad[1]:.0f}) lies beyond the "
                                      f"equidistant model's one-to-one range "
                                      f"({math.degrees(kb.theta_max_rad):.1f} deg)")
    theta = np.arccos(np.clip(bearings[:, 2], -1.0, 1.0))
    theta_max = float(theta.max())
    fov_deg = float(min(359.0, math.ceil(2.0 * math.degrees(theta_max))))
    # The unified model is one-to-one for z_s > -1/xi: keep every sample's ray there.
    xi_max = XI_MAX if theta_max <= math.pi / 2 else min(XI_MAX, -0.99 / math.cos(theta_max))
    radial = _RadialSamples(kb, bearings, theta)

    def fitted(with_distortion: bool) -> tuple[CameraModel, FloatArray]:
        # Variable projection: the profile is linear in (g, g k1, g k2) for a given xi,
        # so only xi is searched (a coarse grid, then Brent's method around its best).
        def cost(xi: float) -> float:
            return radial.solve(xi, with_distortion)[1]

        grid = np.linspace(0.0, xi_max, 25)
        best = int(np.argmin([cost(xi) for xi in grid]))
        low, high = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
        xi = float(minimize_scalar(cost, bounds=(low, high), method="bounded",
                                   options={"xatol": 1e-7}).x)
        g, k1, k2 = radial.solve(xi, with_distortion)[0]
        K = [[g * kb.fx, 0.0, kb.cx], [0.0, g * kb.fy, kb.cy], [0.0, 0.0, 1.0]]
        camera = CameraModel(kb.width, kb.height, K, xi, [k1, k2, 0.0, 0.0], fov_deg)
        projected, ok = camera.project(bearings)
        errors = np.linalg.norm(projected - pixels, axis=1)
        return camera, np.where(ok, errors, np.inf)

    camera, errors = fitted(with_distortion=False)
    with_distortion = bool(errors.max() > DISTORTION_ABOVE_PX)
    if with_distortion:
        camera, errors = fitted(with_distortion=True)
    if not (np.all(np.isfinite(errors)) and abs(camera.D[0]) <= K_MAX
            and abs(camera.D[1]) <= K_MAX):
        raise CalibrationError(where, f"the unified model fitted (xi {camera.xi:.4g}, k1 "
                                      f"{camera.D[0]:.4g}, k2 {camera.D[1]:.4g}) does not map "
                                      "the whole image: no unified camera found")
    return UnifiedFit(camera, float(np.sqrt(np.mean(errors**2))), float(errors.max()),
                      with_distortion, len(pixels))


class _RadialSamples:
    """The fit's samples reduced to the radial profile both models share.

    A pixel at angle theta off the axis and azimuth phi lies at ``f(phi) theta_d`` px from
    the principal point in the equidistant model and at ``f(phi) g rho`` in the unified
    one, with ``f(phi) = |(fx cos phi, fy sin phi)|``, ``rho = m (1 + k1 m^2 + k2 m^4)``
    and ``m = sin(theta) / (cos(theta) + xi)`` (:mod:`shared.camera_model`), so the pixel
    error is ``f(phi) |g rho - theta_d|``: linear least squares in ``(g, g k1, g k2)``.
    """

    def __init__(self, kb: KannalaBrandtCamera, bearings: FloatArray, theta: FloatArray) -> None:
        phi = np.arctan2(bearings[:, 1], bearings[:, 0])
        self.weight = np.hypot(kb.fx * np.cos(phi), kb.fy * np.sin(phi))
        self.theta = theta
        self.target = self.weight * kb.theta_d(theta)

    def solve(self, xi: float, with_distortion: bool) -> tuple[tuple[float, float, float], float]:
        """((g, k1, k2), sum of squared pixel errors) for this xi (k1 = k2 = 0 without
        distortion)."""
        m = np.sin(self.theta) / (np.cos(self.theta) + xi)
        columns = [m, m**3, m**5] if with_distortion else [m]
        A = np.stack(columns, axis=1) * self.weight[:, None]
        coef, *_ = np.linalg.lstsq(A, self.target, rcond=None)
        sse = float(np.sum((A @ coef - self.target) ** 2))
        g = float(coef[0])
        if not with_distortion:
            return (g, 0.0, 0.0), sse
        return (g, float(coef[1] / g), float(coef[2] / g)), sse
