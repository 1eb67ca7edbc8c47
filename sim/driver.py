"""A scripted driver: pure pursuit along a polyline of waypoints.

Used to move the simulated robot without a human (benchmarks, tests; the teach
driver of later issues builds on it). Pure: pose in, (v, omega) out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.pose import Pose2


@dataclass(frozen=True, slots=True)
class DriveCommand:
    """A unicycle command: forward speed (m/s) and turn rate (rad/s, CCW positive)."""

    v_m_s: float
    omega_rad_s: float


class PurePursuit:
    """Follows a polyline with a pure-pursuit law (Coulter, CMU-RI-TR-92-01).

    The robot steers toward the point ``lookahead_m`` ahead of its projection on
    the path; curvature = 2 sin(alpha) / lookahead. Speed drops in sharp turns.
    When the robot is on the path's last stretch and within ``goal_tolerance_m``
    of its end, the command is zero and :attr:`done` becomes true (a loop that
    passes near its own end earlier is driven in full).

    Args:
        waypoints_xy: (N, 2) float64 path vertices on the floor plan, m (N >= 2).
        speed_m_s: cruise speed, m/s.
        lookahead_m: look-ahead distance, m.
        max_omega_rad_s: turn-rate limit, rad/s.
        goal_tolerance_m: distance to the last waypoint that ends the drive, m.
    """

    def __init__(
        self,
        waypoints_xy: npt.ArrayLike,
        speed_m_s: float = 0.4,
        lookahead_m: float = 0.8,
        max_omega_rad_s: float = 1.0,
        goal_tolerance_m: float = 0.25,
    ) -> None:
        pts = np.asarray(waypoints_xy, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 2:
            raise ValueError(f"waypoints_xy must be (N >= 2, 2), got {pts.shape}")
        self._pts = pts
        seg = np.diff(pts, axis=0)
        self._seg_len = np.hypot(seg[:, 0], seg[:, 1])
        self._cum = np.concatenate([[0.0], np.cumsum(self._seg_len)])
        self.speed_m_s = speed_m_s
        self.lookahead_m = lookahead_m
        self.max_omega_rad_s = max_omega_rad_s
        self.goal_tolerance_m = goal_tolerance_m
        self._s = 0.0
        self.done = False

    @property
    def length_m(self) -> float:
        """Total path length, m."""
        return float(self._cum[-1])

    def command(self, pose_w: Pose2) -> DriveCommand:
        """The command for the robot at ``pose_w``, world frame."""
        x, y, yaw = pose_w
        end = self._pts[-1]
        if not self.done:
            self._s = self._progress(x, y)
            # The end counts only once the robot is on the path's last stretch: a path
            # that passes close to its own end earlier (a loop) is driven in full.
            on_last_stretch = self._s >= self.length_m - self.lookahead_m - self.goal_tolerance_m
            near_end = math.hypot(end[0] - x, end[1] - y) < self.goal_tolerance_m
            self.done = on_last_stretch and near_end
        if self.done:
            return DriveCommand(0.0, 0.0)
        tx, ty = self._point_at(min(self._s + self.lookahead_m, self.length_m))
        alpha = math.atan2(ty - y, tx - x) - yaw
        alpha = math.atan2(math.sin(alpha), math.cos(alpha))
        curvature = 2.0 * math.sin(alpha) / self.lookahead_m
        v = self.speed_m_s * max(0.25, math.cos(alpha))
        omega = max(-self.max_omega_rad_s, min(self.max_omega_rad_s, v * curvature))
        return DriveCommand(v, omega)

    def _progress(self, x: float, y: float) -> float:
        """Arc length of the closest path point, searched forward of the last progress only."""
        a = self._pts[:-1]
        seg = np.diff(self._pts, axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.clip(
                ((x - a[:, 0]) * seg[:, 0] + (y - a[:, 1]) * seg[:, 1]) / self._seg_len**2, 0.0, 1.0
            )
        t = np.nan_to_num(t)
        px, py = a[:, 0] + t * seg[:, 0], a[:, 1] + t * seg[:, 1]
        s = self._cum[:-1] + t * self._seg_len
        d = np.hypot(px - x, py - y)
        d[s < self._s - 1e-9] = np.inf  # never go back along the path
        d[s > self._s + 2.0 * self.lookahead_m + 1.0] = (
            np.inf
        )  # nor jump to a far part that passes close
        k = int(np.argmin(d))
        return float(s[k]) if np.isfinite(d[k]) else self._s

    def _point_at(self, s: float) -> tuple[float, float]:
        k = int(np.clip(np.searchsorted(self._cum, s, side="right") - 1, 0, len(self._seg_len) - 1))
        t = (s - self._cum[k]) / self._seg_len[k] if self._seg_len[k] > 0 else 0.0
        p = self._pts[k] + t * (self._pts[k + 1] - self._pts[k])
        return float(p[0]), float(p[1])
