"""The fisheye camera: unified sphere model of Mei and Barreto, as ``cv2.omnidir`` defines it.

Projection of a point ``X_c`` (camera frame: z along the optical axis, x right,
y down in the image) to a pixel (Mei & Rives, ICRA 2007, eqs. 1-5; the code
path of ``cv::omnidir::projectPoints``)::

    X_s = X_c / |X_c|                               onto the unit sphere
    m   = (x_s / (z_s + xi), y_s / (z_s + xi))      onto the normalised plane
    r2  = m_x^2 + m_y^2
    d_x = m_x (1 + k1 r2 + k2 r2^2) + 2 p1 m_x m_y + p2 (r2 + 2 m_x^2)
    d_y = m_y (1 + k1 r2 + k2 r2^2) + p1 (r2 + 2 m_y^2) + 2 p2 m_x m_y
    u   = fx d_x + s d_y + cx,   v = fy d_y + cy

Lifting inverts this exactly, including rays more than 90 degrees off the axis
(z_s < 0), which ``cv2.omnidir.undistortPoints`` folds onto their antipodes:
Newton's method undoes the distortion, then the closed-form sphere lift
(Mei & Rives, eq. 6)::

    lambda = (xi + sqrt(1 + (1 - xi^2) r2)) / (r2 + 1),  X_s = (lambda m_x, lambda m_y, lambda - xi)

Validity: a ray is valid when it lies within half the lens field of view of the
optical axis, the model is one-to-one there (``z_s > -1/xi`` when xi > 1), and
its pixel lies inside the image. Pixel coordinates follow OpenCV: the centre of
the top-left pixel is (0, 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from shared.errors import ShapeError, check_shape

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

#: Newton iterations are stopped when the distortion residual falls below this (normalised units).
_NEWTON_TOL = 1e-15
_NEWTON_MAX_ITER = 30


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Intrinsics of a fisheye camera in the unified sphere model.

    Attributes:
        width: image width, px.
        height: image height, px.
        K: (3, 3) float64 camera matrix ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]``, px.
        xi: sphere-to-plane offset of the unified model (>= 0, dimensionless); a
            size-1 array (as ``cv2.omnidir.calibrate`` returns) is accepted.
        D: (4,) float64 distortion ``(k1, k2, p1, p2)`` on the normalised plane;
            any size-4 array, e.g. OpenCV's (1, 4), is accepted.
        fov_deg: full field of view of the lens, degrees (rays beyond half of it are invalid).
    """

    width: int
    height: int
    K: FloatArray
    xi: float
    D: FloatArray = field(default_factory=lambda: np.zeros(4))
    fov_deg: float = 185.0

    def __post_init__(self) -> None:
        K = np.asarray(self.K, dtype=np.float64)
        D = np.asarray(self.D, dtype=np.float64).reshape(-1)
        check_shape("K", K.shape, (3, 3))
        check_shape("D", D.shape, (4,))
        K.setflags(write=False)
        D.setflags(write=False)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "D", D)
        # xi may come straight from cv2.omnidir.calibrate as a (1, 1) array.
        xi = np.asarray(self.xi, dtype=np.float64)
        if xi.size != 1:
            raise ShapeError(f"xi: expected a scalar or a size-1 array, got shape {xi.shape}")
        object.__setattr__(self, "xi", float(xi.reshape(())))
        object.__setattr__(self, "fov_deg", float(self.fov_deg))

    @classmethod
    def default(cls) -> CameraModel:
        """The default camera: 800x600, 185 degree field of view, no distortion.

        xi = 1.6 makes the lens close to equidistant (about 174 px/rad from the
        centre to the rim), and the 92.5 degree ray lands 290 px from the centre,
        so the image circle fits the 600 px height with a small margin.
        """
        xi = 1.6
        half_fov = math.radians(92.5)
        f = 290.0 * (math.cos(half_fov) + xi) / math.sin(half_fov)
        K = np.array([[f, 0.0, 399.5], [0.0, f, 299.5], [0.0, 0.0, 1.0]])
        return cls(width=800, height=600, K=K, xi=xi, D=np.zeros(4), fov_deg=185.0)

    @property
    def has_distortion(self) -> bool:
        """Whether any of k1, k2, p1, p2 is non-zero."""
        return bool(np.any(self.D != 0.0))

    @property
    def min_z_s(self) -> float:
        """Smallest z of a valid unit bearing: the FOV cone, and ``z_s > -1/xi`` for xi > 1."""
        z_fov = math.cos(math.radians(self.fov_deg / 2.0))
        if self.xi > 1.0:
            return max(z_fov, -1.0 / self.xi)
        return max(z_fov, -self.xi)

    def project(self, points_c: npt.ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Project camera-frame directions or points to pixels.

        Args:
            points_c: (N, 3) bearings or points in the camera frame (any non-zero
                length; only the direction matters).

        Returns:
            pixels_xy: (N, 2) float64 pixel coordinates (meaningless where invalid).
            valid: (N,) bool, the ray is inside the FOV, where the model is
                one-to-one, and its pixel is inside the image.

        Raises:
            ShapeError: ``points_c`` is not (N, 3).
        """
        X = np.asarray(points_c, dtype=np.float64)
        check_shape("points_c", X.shape, (None, 3))
        norm = np.sqrt(np.einsum("ij,ij->i", X, X))
        with np.errstate(divide="ignore", invalid="ignore"):
            Xs = X / norm[:, None]
            denom = Xs[:, 2] + self.xi
            mx = Xs[:, 0] / denom
            my = Xs[:, 1] / denom
            dx, dy = self._distort(mx, my)
        K = self.K
        pixels = np.empty((X.shape[0], 2))
        pixels[:, 0] = K[0, 0] * dx + K[0, 1] * dy + K[0, 2]
        pixels[:, 1] = K[1, 1] * dy + K[1, 2]
        valid = (norm > 0) & (Xs[:, 2] > self.min_z_s) & self._inside(pixels)
        return pixels, valid

    def lift(self, pixels_xy: npt.ArrayLike) -> tuple[FloatArray, BoolArray]:
        """Lift pixels to unit bearings in the camera frame (exact beyond 90 degrees).

        Args:
            pixels_xy: (N, 2) pixel coordinates, px.

        Returns:
            bearings_c: (N, 3) float64 unit rows, camera frame (NaN where the
                model has no preimage).
            valid: (N,) bool, the pixel is inside the image and its ray is a
                valid ray of :meth:`project`.

        Raises:
            ShapeError: ``pixels_xy`` is not (N, 2).
        """
        p = np.asarray(pixels_xy, dtype=np.float64)
        check_shape("pixels_xy", p.shape, (None, 2))
        K = self.K
        dy = (p[:, 1] - K[1, 2]) / K[1, 1]
        dx = (p[:, 0] - K[0, 2] - K[0, 1] * dy) / K[0, 0]
        mx, my, converged = self._undistort(dx, dy)
        r2 = mx * mx + my * my
        disc = 1.0 + (1.0 - self.xi * self.xi) * r2
        with np.errstate(invalid="ignore"):
            lam = (self.xi + np.sqrt(disc)) / (r2 + 1.0)
        bearings = np.stack([lam * mx, lam * my, lam - self.xi], axis=1)
        with np.errstate(invalid="ignore"):
            valid = converged & (disc >= 0.0) & (bearings[:, 2] > self.min_z_s) & self._inside(p)
        return bearings, valid

    def _inside(self, pixels: FloatArray) -> BoolArray:
        u, v = pixels[:, 0], pixels[:, 1]
        with np.errstate(invalid="ignore"):
            return (u >= -0.5) & (u < self.width - 0.5) & (v >= -0.5) & (v < self.height - 0.5)

    def _distort(self, mx: FloatArray, my: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Radial-tangential distortion on the normalised plane (cv2.omnidir's)."""
        if not self.has_distortion:
            return mx, my
        k1, k2, p1, p2 = self.D
        r2 = mx * mx + my * my
        radial = 1.0 + k1 * r2 + k2 * r2 * r2
        dx = mx * radial + 2.0 * p1 * mx * my + p2 * (r2 + 2.0 * mx * mx)
        dy = my * radial + p1 * (r2 + 2.0 * my * my) + 2.0 * p2 * mx * my
        return dx, dy

    def _undistort(
        self, dx: FloatArray, dy: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoolArray]:
        """Invert :meth:`_distort` by Newton's method on the 2x2 system.

        Returns:
            mx, my: (N,) undistorted normalised coordinates.
            converged: (N,) bool, the residual fell below tolerance.
        """
        if not self.has_distortion:
            return dx, dy, np.isfinite(dx) & np.isfinite(dy)
        k1, k2, p1, p2 = self.D
        mx, my = dx.copy(), dy.copy()
        for _ in range(_NEWTON_MAX_ITER):
            fx, fy = self._distort(mx, my)
            ex, ey = fx - dx, fy - dy
            if np.all(np.abs(ex) + np.abs(ey) < _NEWTON_TOL):
                break
            r2 = mx * mx + my * my
            radial = 1.0 + k1 * r2 + k2 * r2 * r2
            dradial = 2.0 * (k1 + 2.0 * k2 * r2)  # d(radial)/dx = dradial * x
            j11 = radial + dradial * mx * mx + 2.0 * p1 * my + 6.0 * p2 * mx
            j12 = dradial * mx * my + 2.0 * p1 * mx + 2.0 * p2 * my
            j21 = dradial * mx * my + 2.0 * p1 * mx + 2.0 * p2 * my
            j22 = radial + dradial * my * my + 6.0 * p1 * my + 2.0 * p2 * mx
            det = j11 * j22 - j12 * j21
            with np.errstate(divide="ignore", invalid="ignore"):
                mx = mx - (j22 * ex - j12 * ey) / det
                my = my - (j11 * ey - j21 * ex) / det
        fx, fy = self._distort(mx, my)
        with np.errstate(invalid="ignore"):
            converged = (np.abs(fx - dx) + np.abs(fy - dy)) < 1e-12
        return mx, my, converged
