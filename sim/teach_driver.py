"""The scripted teach driver: a route driven like a person would, smooth but not exact.

A person teaching a route steers by eye: the robot wanders a few centimetres
either side of the line over metres of travel, and its speed drifts a little.
Here that is pure pursuit (:class:`sim.driver.PurePursuit`) of the route shifted
sideways by a smooth random *wander* w(s), with the cruise speed scaled by
1 + g(s), both functions of the distance s along the route:

* w(s) and g(s) are sums of three sinusoids in s with random wavelengths in
  ``wander_wavelength_m``, phases and weights, scaled to peak at
  ``wander_amplitude_m`` and ``speed_variation``. Wavelengths of metres are
  well above the look-ahead distance, so pure pursuit follows the wander
  instead of filtering it out;
* the wander fades in over the first and out over the last ``_TAPER_M`` of
  the route (smoothstep), so the drive starts and ends on the route's
  waypoints, where other routes meet it;
* the speed drops linearly over the last ``_SLOWDOWN_M`` before the end, to
  ``_MIN_SPEED_FRACTION`` of the cruise speed, instead of braking at the goal.

Pure and deterministic: the random draws happen once, from the generator passed
in; then pose in, command out.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import numpy.typing as npt

from shared.pose import Pose2
from sim.config import TeachDriverConfig
from sim.driver import DriveCommand, PurePursuit

FloatArray = npt.NDArray[np.float64]

_SAMPLE_STEP_M = 0.05
"""Spacing of the resampled route that carries the wander, m."""
_COMPONENTS = 3
"""Sinusoids summed in each of w(s) and g(s)."""
_TAPER_M = 1.0
"""The wander fades in over this distance after the start and out before the end, m."""
_SLOWDOWN_M = 0.6
"""The speed ramps down over this distance before the end, m."""
_MIN_SPEED_FRACTION = 0.3
"""Fraction of the cruise speed left at the end of the slow-down."""


def resample_polyline(waypoints_xy: FloatArray, step_m: float) -> tuple[FloatArray, FloatArray]:
    """Points every ``step_m`` along a polyline, with every vertex kept.

    Args:
        waypoints_xy: (N, 2) float64 vertices, m, N >= 2, no two consecutive equal.
        step_m: the largest spacing of the output, m.

    Returns:
        ``(points_xy (M, 2), s_m (M,))``: the points and their arc length from the start.
    """
    points: list[FloatArray] = []
    for a, b in itertools.pairwise(waypoints_xy):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step_m))
        t = np.arange(n)[:, None] / n
        points.append(a + t * (b - a))
    points.append(waypoints_xy[-1:])
    pts = np.concatenate(points)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    return pts, s


def smooth_noise(
    s_m: FloatArray,
    peak: float,
    wavelengths_m: tuple[float, float],
    rng: np.random.Generator,
) -> FloatArray:
    """A smooth random function of arc length: a sum of sinusoids scaled to peak at ``peak``.

    Args:
        s_m: (M,) arc lengths where it is sampled, m.
        peak: the largest absolute value over ``s_m``.
        wavelengths_m: (low, high) range of the sinusoids' wavelengths, m.
        rng: draws wavelengths, phases and weights.

    Returns:
        (M,) float64 values in [-peak, peak]; all zero when ``peak`` is 0.
    """
    wavelength = rng.uniform(*wavelengths_m, size=_COMPONENTS)
    phase = rng.uniform(0.0, 2.0 * math.pi, size=_COMPONENTS)
    weight = rng.uniform(0.5, 1.0, size=_COMPONENTS)
    values = (weight * np.sin(2.0 * math.pi * s_m[:, None] / wavelength + phase)).sum(axis=1)
    largest = float(np.abs(values).max())
    return values * (peak / largest) if largest > 0.0 else np.zeros_like(s_m)


def _smoothstep(x: FloatArray) -> FloatArray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


class TeachDriver:
    """Drives along a route like a person teaching it (see the module docstring).

    Args:
        waypoints_xy: (N, 2) route vertices on the floor plan, m (N >= 2).
        config: cruise speed, wander, look-ahead and turn-rate limit.
        rng: the random draws of the wander and the speed drift (made here, once).

    Attributes:
        path_xy: (M, 2) float64 the wandering line that is pursued, m.
        route_s_m: (M,) float64 arc length along the route of each point of ``path_xy``, m.
        wander_m: (M,) float64 lateral offset of each point from the route, left positive, m.
    """

    def __init__(
        self, waypoints_xy: npt.ArrayLike, config: TeachDriverConfig, rng: np.random.Generator
    ) -> None:
        route = np.asarray(waypoints_xy, dtype=np.float64)
        if route.ndim != 2 or route.shape[1] != 2 or route.shape[0] < 2:
            raise ValueError(f"waypoints_xy must be (N >= 2, 2), got {route.shape}")
        self.config = config
        points, s = resample_polyline(route, _SAMPLE_STEP_M)
        length = float(s[-1])
        taper = _smoothstep(s / _TAPER_M) * _smoothstep((length - s) / _TAPER_M)
        self.wander_m = (
            smooth_noise(s, config.wander_amplitude_m, config.wander_wavelength_m, rng) * taper
        )
        self._speed_scale = 1.0 + smooth_noise(
            s, config.speed_variation, config.wander_wavelength_m, rng
        )
        tangent = np.gradient(points, axis=0)
        tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
        normal_left = np.column_stack([-tangent[:, 1], tangent[:, 0]])
        self.path_xy = points + self.wander_m[:, None] * normal_left
        self.route_s_m = s
        self._end = route[-1]
        self._pursuit = PurePursuit(
            self.path_xy,
            speed_m_s=config.speed_m_s,
            lookahead_m=config.lookahead_m,
            max_omega_rad_s=config.max_omega_rad_s,
            goal_tolerance_m=config.goal_tolerance_m,
        )
        self._driven_m = 0.0
        self._last_xy: tuple[float, float] | None = None

    @property
    def done(self) -> bool:
        """Whether the end of the route has been reached (the command is then zero)."""
        return self._pursuit.done

    @property
    def length_m(self) -> float:
        """Length of the route, m."""
        return float(self.route_s_m[-1])

    def command(self, pose_w: Pose2) -> DriveCommand:
        """The command for the robot at ``pose_w``, true pose on the floor plan.

        The speed drift is indexed by the distance driven so far (the sum of the
        straight steps between the poses given to successive calls).
        """
        x, y, _ = pose_w
        if self._last_xy is not None:
            self._driven_m += math.hypot(x - self._last_xy[0], y - self._last_xy[1])
        self._last_xy = (x, y)
        scale = float(np.interp(self._driven_m, self.route_s_m, self._speed_scale))
        to_end_m = math.hypot(self._end[0] - x, self._end[1] - y)
        slowdown = max(_MIN_SPEED_FRACTION, min(1.0, to_end_m / _SLOWDOWN_M))
        self._pursuit.speed_m_s = self.config.speed_m_s * scale * slowdown
        return self._pursuit.command(pose_w)
