"""Angular Sampson error of correspondences on the sphere, and its derivatives.

For unit rays f_a, f_b and a pose (R, t) with ``X_b = R X_a + t`` (Hartley &
Zisserman, eq. 9.12: E = [t]x R), the first-order geometric error with isotropic
angular noise on both rays (Sampson's approximation on the sphere; cf. Lee &
Civera, "Geometric interpretations of the normalized epipolar error", 2020)::

    g = f_b^T E f_a,    r = g / sqrt(|P_b E f_a|^2 + |P_a E^T f_b|^2),    P_f = I - f f^T

and since f_b . E f_a = f_a . E^T f_b = g the denominator is
``|E f_a|^2 + |E^T f_b|^2 - 2 g^2``. r is in radians, comparable to one ray's
angular noise, and the same for rays beyond 90 degrees.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

#: Hypotheses scored together (see :meth:`EpipolarPairs.errors`).
_SCORE_CHUNK = 32


def rotation_y(yaw: float) -> FloatArray:
    """Rotation by ``yaw`` about the y axis (PoseLib's upright convention), (3, 3)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rotation_y_derivative(yaw: float) -> FloatArray:
    """d rotation_y / d yaw, (3, 3)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def essentials(Rs: FloatArray, ts: FloatArray) -> FloatArray:
    """(H, 3, 3) essential matrices [t]x R of H poses (Rs (H, 3, 3), ts (H, 3))."""
    S = np.zeros((len(ts), 3, 3))
    S[:, 0, 1], S[:, 0, 2], S[:, 1, 2] = -ts[:, 2], ts[:, 1], -ts[:, 0]
    S[:, 1, 0], S[:, 2, 0], S[:, 2, 1] = ts[:, 2], -ts[:, 1], ts[:, 0]
    return S @ Rs


class EpipolarPairs:
    """Correspondences prepared for fast Sampson errors under many essential matrices.

    The three quadratic forms of the error are linear in the entries of a matrix::

        g           = f_b^T E f_a   = (f_b (x) f_a) . vec(E)
        |E f_a|^2   = (f_a (x) f_a) . vec(E^T E)
        |E^T f_b|^2 = (f_b (x) f_b) . vec(E E^T)

    so with the (N, 9) outer products stored once, errors under H matrices (and
    their derivatives) are three (N, 9) @ (9, H) products.

    Args:
        fa: (N, 3) unit rays in frame a.
        fb: (N, 3) unit rays in frame b.
    """

    def __init__(self, fa: FloatArray, fb: FloatArray) -> None:
        self.ab = (fb[:, :, None] * fa[:, None, :]).reshape(-1, 9)
        self.aa = (fa[:, :, None] * fa[:, None, :]).reshape(-1, 9)
        self.bb = (fb[:, :, None] * fb[:, None, :]).reshape(-1, 9)

    def __len__(self) -> int:
        return len(self.ab)

    def subset(self, rows: npt.NDArray[np.bool_] | npt.NDArray[np.intp]) -> EpipolarPairs:
        """The correspondences selected by a mask or an index array."""
        out = EpipolarPairs.__new__(EpipolarPairs)
        out.ab, out.aa, out.bb = self.ab[rows], self.aa[rows], self.bb[rows]
        return out

    def errors(self, Es: FloatArray) -> FloatArray:
        """(H, N) angular Sampson errors under H essential matrices Es (H, 3, 3).

        Hypotheses go in chunks of :data:`_SCORE_CHUNK` so that the (N, chunk)
        temporaries stay below glibc's mmap threshold (128 KiB), whose page faults
        otherwise cost more than the arithmetic.
        """
        out = np.empty((len(Es), len(self.ab)))
        for lo in range(0, len(Es), _SCORE_CHUNK):
            E = Es[lo:lo + _SCORE_CHUNK]
            g = self.ab @ E.reshape(-1, 9).T
            den = (self.aa @ (E.transpose(0, 2, 1) @ E).reshape(-1, 9).T
                   + self.bb @ (E @ E.transpose(0, 2, 1)).reshape(-1, 9).T - 2.0 * g * g)
            out[lo:lo + _SCORE_CHUNK] = (g / np.sqrt(np.maximum(den, 1e-300))).T
        return out

    def errors_and_derivatives(self, E: FloatArray,
                               dEs: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Errors (N,) under E (3, 3) and their (N, P) derivatives along dE/dx_i = dEs[i].

        With den = |E f_a|^2 + |E^T f_b|^2 - 2 g^2 and r = g / sqrt(den):
        dr = dg / sqrt(den) - g d(den) / (2 den^1.5), dg = (f_b (x) f_a) . vec(dE),
        d(den) = (f_a (x) f_a) . vec(dE^T E + E^T dE) + (f_b (x) f_b) . vec(dE E^T + E dE^T)
        - 4 g dg.
        """
        Et = E.T
        dEt = dEs.transpose(0, 2, 1)
        G = self.ab @ np.concatenate([E[None], dEs]).reshape(-1, 9).T
        A = self.aa @ np.concatenate([(Et @ E)[None], dEt @ E + Et @ dEs]).reshape(-1, 9).T
        B = self.bb @ np.concatenate([(E @ Et)[None], dEs @ Et + E @ dEt]).reshape(-1, 9).T
        g, dg = G[:, 0], G[:, 1:]
        den = np.maximum(A[:, 0] + B[:, 0] - 2.0 * g * g, 1e-300)[:, None]
        dden = A[:, 1:] + B[:, 1:] - 4.0 * g[:, None] * dg
        root = np.sqrt(den)
        return g / root[:, 0], dg / root - 0.5 * g[:, None] * dden / (den * root)
