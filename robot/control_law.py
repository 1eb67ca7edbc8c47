"""The path-following law of Courbon et al. (ICARCV 2008, sec. III-C, eq. 2).

With the state (s, y, theta) of the robot relative to the line Gamma' through the
next key image (:mod:`robot.segment_frame`), the unicycle model is (eq. 1)::

    s' = V cos(theta),   y' = V sin(theta),   theta' = omega.

The chained form a1 = s, a2 = y, a3 = tan(theta) turns it, in the distance s,
into d2y/ds2 = omega / (V cos^3(theta)); eq. (2),

    omega = -V cos^3(theta) Kp y - |V cos^3(theta)| Kd tan(theta),

makes this y'' + Kd y' + Kp y = 0 for V > 0: a linear response to the distance
driven, whatever the speed. A double pole at g (1/m) gives Kp = g^2, Kd = 2 g and,
from y(0) = y0 with the robot parallel to the line, y(s) = y0 (1 + g s) exp(-g s)
(:func:`settling_distance_m`). How the paper's "double pole located at value 0.3"
is read (distance or time domain) is a config choice, :class:`ControlConfig`.

The ``"paper+ff"`` law adds the feed-forward of a reference path of curvature c:
with (s, y, theta) measured from that path (:func:`robot.segment_frame.arc_coordinates`),
the Frenet model is theta' = omega - c V cos(theta) / (1 - c y); adding
omega_ff = c V cos(theta) / (1 - c y) to eq. (2) leaves exactly the straight-line
error dynamics above (Samson 1995, path following in the Frenet frame), so the
robot follows the taught arc instead of converging onto the straight line Gamma'.

|omega| is bounded last (paper: 10 deg/s "for safety"); a bound that cuts the
feed-forward means the turn is tighter than the robot may follow at this speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.special import lambertw

from robot.config import ControlConfig
from shared.errors import DegenerateGeometryError


@dataclass(frozen=True, slots=True)
class Twist:
    """A velocity command for the base (robot frame: x forward, z up).

    Attributes:
        v_m_s: forward speed, m/s.
        omega_rad_s: turn rate, counter-clockwise positive, rad/s.
    """

    v_m_s: float
    omega_rad_s: float


def gains(config: ControlConfig) -> tuple[float, float]:
    """Kp (1/m^2) and Kd (1/m) that put a double pole at ``config.pole_1_m``.

    (s + g)^2 = s^2 + 2 g s + g^2 against s^2 + Kd s + Kp.
    """
    g = config.pole_1_m
    return g * g, 2.0 * g


def steer(
    y_m: float, theta_rad: float, config: ControlConfig, curvature_ff_1_m: float = 0.0
) -> Twist:
    """The velocity command of eq. (2), optionally with curvature feed-forward, bounded.

    Args:
        y_m: lateral error, left positive, m: from the line Gamma' (``law = "paper"``) or
            from the taught arc (``law = "paper+ff"``, see
            :func:`robot.segment_frame.arc_coordinates`).
        theta_rad: heading error (robot yaw minus the reference's), rad.
        config: law, speed, gains and bound.
        curvature_ff_1_m: curvature of the reference path, 1/m, left turns positive
            (:func:`robot.segment_frame.segment_curvature_1_m`); used by the
            ``"paper+ff"`` law only, ignored by ``"paper"``.

    Returns:
        v = ``config.speed_m_s`` and omega with |omega| <= ``config.max_omega_rad_s``.

    Raises:
        ValueError: an argument is not finite.
        DegenerateGeometryError: ``"paper+ff"`` with 1 - c y <= 0 (the robot is at or
            beyond the centre of the reference arc).
    """
    for name, value in (("y_m", y_m), ("theta_rad", theta_rad),
                        ("curvature_ff_1_m", curvature_ff_1_m)):
        if not math.isfinite(value):
            raise ValueError(f"steer: {name} must be finite, got {value}")
    kp, kd = gains(config)
    v = config.speed_m_s
    v_cos3 = v * math.cos(theta_rad) ** 3
    omega = -v_cos3 * kp * y_m - abs(v_cos3) * kd * math.tan(theta_rad)  # eq. (2)
    if config.law == "paper+ff" and curvature_ff_1_m != 0.0:
        c = curvature_ff_1_m
        closeness = 1.0 - c * y_m
        if closeness <= 0.0:
            raise DegenerateGeometryError(
                f"robot at or beyond the centre of the reference arc: 1 - c y = {closeness:.3g} "
                f"(c = {c:.3g} 1/m, y = {y_m:.3g} m)")
        omega += c * v * math.cos(theta_rad) / closeness
    bound = config.max_omega_rad_s
    return Twist(v_m_s=v, omega_rad_s=min(bound, max(-bound, omega)))


def settling_distance_m(pole_1_m: float, y0_m: float, tolerance_m: float) -> float:
    """Distance after which |y| stays below ``tolerance_m`` (linear law, no bound, no delay).

    Solves y0 (1 + x) exp(-x) = tolerance for x = g s on the decreasing branch:
    x = -1 - W_{-1}(-r / e) with r = tolerance / |y0| (Lambert W, lower branch).

    Args:
        pole_1_m: the double pole g, 1/m (:attr:`ControlConfig.pole_1_m`).
        y0_m: the initial lateral error (robot parallel to the line), m.
        tolerance_m: the band, m, > 0.

    Returns:
        The distance, m (0 when |y0| is already within the band).

    Raises:
        ValueError: ``pole_1_m`` or ``tolerance_m`` is not > 0.
    """
    if not pole_1_m > 0:
        raise ValueError(f"settling_distance_m: pole_1_m must be > 0, got {pole_1_m}")
    if not tolerance_m > 0:
        raise ValueError(f"settling_distance_m: tolerance_m must be > 0, got {tolerance_m}")
    ratio = tolerance_m / abs(y0_m) if y0_m != 0 else math.inf
    if ratio >= 1.0:
        return 0.0
    x = -1.0 - lambertw(-ratio / math.e, k=-1).real
    return float(x / pole_1_m)
