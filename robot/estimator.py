"""The robot's state relative to the next key image, filtered: odometry predicts, vision updates.

A filterpy Kalman filter over x = (s, y, theta), the robot's pose in the base frame
of the key image it heads for (:mod:`robot.segment_frame`; the frame the vision
measures in, :class:`robot.vision.path_state.PathState`). The control law needs
(y, theta); s is kept in the filter too because moving the state to the next key
image's frame mixes s into y (:func:`robot.segment_frame.coordinates_in_next_segment`)
and because the key image switching rule "passed the key image" must keep working
on odometry alone between vision estimates.

Rules of use, once per servo cycle:

1. :meth:`Estimator.predict` with the base's odometry since the previous call:
   forward distance ds and heading change dpsi. Eq. (1) of Courbon et al. 2008
   integrated exactly along a constant-curvature step: the chord has length
   k ds with k = sin(dpsi/2) / (dpsi/2) and the mean heading theta_mid = theta +
   dpsi/2, so s += k ds cos(theta_mid), y += k ds sin(theta_mid), theta += dpsi.
   The reference line is fixed, so no path curvature enters here; the control
   law's curvature feed-forward re-expresses the estimate relative to the taught
   arc instead (:func:`robot.segment_frame.arc_coordinates`).
2. :meth:`Estimator.update` with the vision estimate when one is usable; frames
   without one simply skip it, and the filter coasts on odometry. An estimate far
   from the prediction (Mahalanobis gate) is rejected and counted.
3. :meth:`Estimator.poll` with the time: after ``lost_timeout_ns`` without an
   accepted estimate, or after ``lost_distance_m`` driven on odometry alone, it
   returns one :class:`EstimatorLost` event (once per episode): a robot without
   verified localization does not drive on blind. The first estimate after LOST
   re-initialises the filter, ungated. Time the robot stood still for the safety
   layer (:meth:`Estimator.stood_still`) does not count.

Before its first estimate (and after :meth:`Estimator.reset`) the filter holds no
state and :attr:`Estimator.estimate` is None. At a key image switch,
:meth:`Estimator.switch_segment` moves mean and covariance to the next key image's
frame (a rigid transform, so exactly). Vision latency is not modelled: an estimate
is applied when it arrives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from filterpy.kalman import KalmanFilter

from robot.config import EstimatorConfig
from robot.segment_frame import coordinates_in_next_segment, wrap_angle
from robot.vision.path_state import PathCoordinates
from shared.pose import Pose2

FloatArray = npt.NDArray[np.float64]

_S, _Y, _THETA = 0, 1, 2


@dataclass(frozen=True, eq=False)
class Estimate:
    """The filtered state.

    Attributes:
        s_m: along-track position relative to the next key image, negative before it, m.
        y_m: lateral error from the key image's line, left positive, m.
        theta_rad: heading relative to the key image's, rad in (-pi, pi].
        covariance: (3, 3) float64 covariance of (s, y, theta), m and rad.
        t_update_ns: time of the last accepted vision estimate, ns.
    """

    s_m: float
    y_m: float
    theta_rad: float
    covariance: FloatArray
    t_update_ns: int


@dataclass(frozen=True, slots=True)
class UpdateResult:
    """What :meth:`Estimator.update` did with a vision estimate.

    Attributes:
        outcome: "initialized" (first estimate, or first after LOST or a reset),
            "accepted" or "rejected" (outside the gate).
        mahalanobis2: squared Mahalanobis distance of the innovation (0 when initialised).
    """

    outcome: str
    mahalanobis2: float

    @property
    def used(self) -> bool:
        """The estimate entered the filter."""
        return self.outcome != "rejected"


@dataclass(frozen=True, slots=True)
class EstimatorLost:
    """No usable vision estimate for too long: the state is not known any more.

    Attributes:
        t_ns: when LOST was declared, ns.
        reason: "no_estimate" (vision gave nothing usable) or "rejected" (estimates came
            but all fell outside the gate).
        since_update_ns: time since the last accepted estimate (or the reset), ns.
        limit_ns: the configured timeout, ns.
        rejected: estimates rejected by the gate in that time.
        driven_m: distance driven on odometry alone in that time, m.
        limit_m: the configured distance, m.
    """

    t_ns: int
    reason: str
    since_update_ns: int
    limit_ns: int
    rejected: int
    driven_m: float = 0.0
    limit_m: float = math.inf

    @property
    def message(self) -> str:
        """One line for logs and telemetry."""
        what = (f"{self.rejected} estimates rejected by the gate" if self.reason == "rejected"
                else "no usable vision estimate")
        if self.driven_m >= self.limit_m:
            return f"{what} for {self.driven_m:.2f} m driven (limit {self.limit_m:.2f} m)"
        return (f"{what} for {self.since_update_ns / 1e9:.2f} s "
                f"(limit {self.limit_ns / 1e9:.2f} s)")


class Estimator:
    """Kalman filter over (s, y, theta) relative to the next key image.

    Args:
        config: noise model, gate and LOST timeout.
        now_ns: the current time, ns; the LOST timer starts here.
    """

    def __init__(self, config: EstimatorConfig, now_ns: int) -> None:
        self._config = config
        self._R = np.diag([config.sigma_s_m**2, config.sigma_y_m**2, config.sigma_theta_rad**2])
        self._kf = KalmanFilter(dim_x=3, dim_z=3)
        self._kf.H = np.eye(3)
        self._kf.R = self._R.copy()
        self._initialized = False
        self._lost = False
        self._t_last_ns = now_ns
        self._t_update_ns = now_ns
        self._rejected = 0
        self._driven_m = 0.0  # on odometry alone since the last accepted estimate

    @property
    def estimate(self) -> Estimate | None:
        """The current state, or None before the first estimate (or after a reset)."""
        if not self._initialized:
            return None
        x = self._kf.x[:, 0]
        return Estimate(s_m=float(x[_S]), y_m=float(x[_Y]), theta_rad=float(x[_THETA]),
                        covariance=self._kf.P.copy(), t_update_ns=self._t_update_ns)

    @property
    def tracking(self) -> bool:
        """An estimate exists and LOST was not declared since: vision updates are gated."""
        return self._initialized and not self._lost

    @property
    def lost(self) -> bool:
        """LOST was declared and no estimate has been accepted since."""
        return self._lost

    def reset(self, now_ns: int) -> None:
        """Forget the state (e.g. after relocalization); the LOST timer restarts at ``now_ns``."""
        self._check_time(now_ns)
        self._initialized = False
        self._lost = False
        self._t_update_ns = now_ns
        self._rejected = 0
        self._driven_m = 0.0

    def stood_still(self, duration_ns: int) -> None:
        """The robot stood still for ``duration_ns`` (a safety wait, ns): that time does
        not count towards ``lost_timeout_ns`` (odometry saw no motion to drift)."""
        self._t_update_ns += max(duration_ns, 0)

    def predict(self, ds_m: float, dpsi_rad: float) -> None:
        """Move the state by the base's odometry since the last call.

        Args:
            ds_m: forward distance driven, m (negative when reversing).
            dpsi_rad: heading change, counter-clockwise positive, rad.

        Raises:
            ValueError: an increment is not finite.
        """
        for name, value in (("ds_m", ds_m), ("dpsi_rad", dpsi_rad)):
            if not math.isfinite(value):
                raise ValueError(f"Estimator.predict: {name} must be finite, got {value}")
        self._driven_m += abs(ds_m)
        if not self._initialized:
            return
        s, y, theta = self._kf.x[:, 0]
        mid = theta + 0.5 * dpsi_rad
        chord = ds_m * float(np.sinc(0.5 * dpsi_rad / math.pi))  # np.sinc(x) = sin(pi x)/(pi x)
        cos_mid, sin_mid = math.cos(mid), math.sin(mid)
        moved = np.array([s + chord * cos_mid, y + chord * sin_mid, theta + dpsi_rad])
        F = np.array([[1.0, 0.0, -chord * sin_mid],
                      [0.0, 1.0, chord * cos_mid],
                      [0.0, 0.0, 1.0]])
        cfg = self._config
        dist = abs(ds_m)
        Q = np.diag([cfg.process_var_position_m2_per_m * dist,
                     cfg.process_var_position_m2_per_m * dist,
                     cfg.process_var_theta_rad2_per_m * dist
                     + (cfg.rotation_scale_sigma * dpsi_rad) ** 2])
        # Linearised about the mean (an EKF step): x' = F x + (f(x_hat) - F x_hat), so
        # filterpy's x = F x + B u carries the mean exactly and P = F P F^T + Q.
        self._kf.predict(u=(moved - F @ self._kf.x[:, 0])[:, None], B=np.eye(3), F=F, Q=Q)
        self._kf.x[_THETA, 0] = wrap_angle(float(self._kf.x[_THETA, 0]))

    def update(self, now_ns: int, s_m: float, y_m: float, theta_rad: float) -> UpdateResult:
        """Fuse one vision estimate of the state (covariance from the config).

        Args:
            now_ns: the time, ns (not before any earlier call's).
            s_m: along-track position relative to the next key image, m.
            y_m: lateral error, left positive, m.
            theta_rad: heading error, rad.

        Returns:
            What happened to the estimate.

        Raises:
            ValueError: a value is not finite.
            ValueError: ``now_ns`` is earlier than a previous call's.
        """
        for name, value in (("s_m", s_m), ("y_m", y_m), ("theta_rad", theta_rad)):
            if not math.isfinite(value):
                raise ValueError(f"Estimator.update: {name} must be finite, got {value}")
        self._check_time(now_ns)
        if not self._initialized or self._lost:
            self._kf.x = np.array([[s_m], [y_m], [wrap_angle(theta_rad)]])
            self._kf.P = self._R.copy()
            self._accept(now_ns)
            return UpdateResult("initialized", 0.0)
        x = self._kf.x[:, 0]
        # Compare theta on the circle: the measurement is moved next to the prediction.
        z = np.array([s_m, y_m, x[_THETA] + wrap_angle(theta_rad - x[_THETA])])
        innovation = z - x
        S = self._kf.P + self._R
        d2 = float(innovation @ np.linalg.solve(S, innovation))
        gate = self._config.gate_chi2
        if gate is not None and d2 > gate:
            self._rejected += 1
            return UpdateResult("rejected", d2)
        self._kf.update(z[:, None])
        self._kf.x[_THETA, 0] = wrap_angle(float(self._kf.x[_THETA, 0]))
        self._accept(now_ns)
        return UpdateResult("accepted", d2)

    def poll(self, now_ns: int) -> EstimatorLost | None:
        """Declare LOST once ``lost_timeout_ns`` has passed without an accepted estimate.

        Args:
            now_ns: the time, ns (not before any earlier call's).

        Returns:
            The event, at the first poll at or after the timeout; None otherwise (also
            while LOST persists).

        Raises:
            ValueError: ``now_ns`` is earlier than a previous call's.
        """
        self._check_time(now_ns)
        since_ns = now_ns - self._t_update_ns
        limit_ns, limit_m = self._config.lost_timeout_ns, self._config.lost_distance_m
        if self._lost or (since_ns < limit_ns and self._driven_m < limit_m):
            return None
        self._lost = True
        return EstimatorLost(t_ns=now_ns, reason="rejected" if self._rejected else "no_estimate",
                             since_update_ns=since_ns, limit_ns=limit_ns,
                             rejected=self._rejected, driven_m=self._driven_m, limit_m=limit_m)

    def switch_segment(self, next_in_current: Pose2) -> None:
        """Re-express the state relative to the following key image (at a key image switch).

        Args:
            next_in_current: the following key image's pose (x_m, y_m, yaw_rad) in the
                current one's base frame (:func:`robot.segment_frame.relative_pose` of
                their teach odometry poses).
        """
        if not self._initialized:
            return
        s, y, theta = self._kf.x[:, 0]
        moved = coordinates_in_next_segment(PathCoordinates(s, y, theta), next_in_current)
        yaw = next_in_current[2]
        c, sn = math.cos(yaw), math.sin(yaw)
        J = np.array([[c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]])
        self._kf.x = np.array([[moved.s_m], [moved.y_m], [moved.theta_rad]])
        self._kf.P = J @ self._kf.P @ J.T

    def _accept(self, now_ns: int) -> None:
        self._initialized = True
        self._lost = False
        self._t_update_ns = now_ns
        self._rejected = 0
        self._driven_m = 0.0

    def _check_time(self, now_ns: int) -> None:
        if now_ns < self._t_last_ns:
            raise ValueError(
                f"now_ns went backwards: {now_ns} ns after {self._t_last_ns} ns")
        self._t_last_ns = now_ns
