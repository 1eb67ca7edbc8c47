"""Odometry from SIP positions: per-subtype conversion factors and the pose integrator.

The robot integrates its own pose and reports it in the SIP as raw counters
(reference §5): XPOS/YPOS are 15-bit counters in DistConvFactor units that wrap at
0x8000, THPOS is a heading in AngleConvFactor units (about 2 pi / 4096). Like ARIA
(reference §5, "Pose semantics"), the integrator uses only the changes between
consecutive SIPs: the odometry frame is where the robot stood at the first SIP, and
after a reconnect the first SIP of the new session becomes a new raw reference, so
the pose continues without a jump whatever the robot's counters say.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.aria.p3at import SONAR_POSES as P3AT_SONAR_POSES
from shared.aria.sip import Sip, position_delta
from shared.pose import Pose2

HEADING_COUNTS = 4096
"""THPOS counts per turn; any modulo-4096 convention works (reference §5)."""


@dataclass(frozen=True, slots=True)
class RobotParams:
    """The conversion factors ARIA keeps per robot subtype.

    Attributes:
        dist_mm_per_count: DistConvFactor, mm per XPOS/YPOS count.
        angle_rad_per_count: AngleConvFactor, rad per THPOS count.
        diff_conv_rad_per_mm: DiffConvFactor, rad/s of turn rate per mm/s of wheel-speed
            difference (used when the SIP carries no ROTVEL).
        sonar_poses: the ``SonarUnit`` lines: sonar k's (x_m, y_m, heading_rad) in the
            robot frame.
    """

    dist_mm_per_count: float
    angle_rad_per_count: float = 0.001534
    diff_conv_rad_per_mm: float = 0.0034
    sonar_poses: tuple[Pose2, ...] = P3AT_SONAR_POSES


_P3DX_SONAR_POSES: tuple[Pose2, ...] = tuple(
    Pose2(x_mm / 1000, y_mm / 1000, math.radians(th_deg))
    for x_mm, y_mm, th_deg in (
        (69, 136, 90), (114, 119, 50), (148, 78, 30), (166, 27, 10),
        (166, -27, -10), (148, -78, -30), (114, -119, -50), (69, -136, -90),
        (-157, -136, -90), (-203, -119, -130), (-237, -78, -150), (-255, -27, -170),
        (-255, 27, 170), (-237, 78, 150), (-203, 119, 130), (-157, 136, 90),
    )
)

PARAMS_BY_SUBTYPE: dict[str, RobotParams] = {
    "p3at": RobotParams(0.465),
    "p3at-sh": RobotParams(1.0),
    "p3dx": RobotParams(0.485, diff_conv_rad_per_mm=0.0056, sonar_poses=_P3DX_SONAR_POSES),
    "p3dx-sh": RobotParams(1.0, diff_conv_rad_per_mm=0.0056, sonar_poses=_P3DX_SONAR_POSES),
}
"""Subclass (lower case) -> factors. P3-AT: reference §8 (``ArRobotTypes.cpp:1268, 1544``)
and ``params/p3at-sh.p``'s SonarUnit lines (:mod:`shared.aria.p3at`); P3-DX: AriaCoda
``ArRobotTypes.cpp`` (``ArRobotP3DX``, ``ArRobotP3DXSH``) and ``params/p3dx-sh.p``;
AngleConvFactor is ARIA's default 0.001534 for all four."""

DEFAULT_SUBTYPE = "p3at-sh"
"""Assumed for an unknown subclass: the reference's recommended pairing (§8), 1 mm per count."""


def params_for_subtype(subclass: str) -> RobotParams | None:
    """The factors of ``subclass`` (ARIA lower-cases it), or None if unknown."""
    return PARAMS_BY_SUBTYPE.get(subclass.lower())


def heading_delta_counts(previous_counts: int, current_counts: int) -> int:
    """Signed THPOS change, counts, in -2048..2047 (the shorter way round)."""
    half = HEADING_COUNTS // 2
    return (current_counts - previous_counts + half) % HEADING_COUNTS - half


class Odometry:
    """Integrates SIP position counters into a pose in the odometry frame.

    The robot's own frame differs from the odometry frame by a rotation (and a
    translation that deltas do not see), fixed for one session: changes reported in
    the robot's frame are rotated by ``offset = th_odom - th_robot``, taken at the
    session's first SIP.
    """

    def __init__(self) -> None:
        self._x_m = 0.0
        self._y_m = 0.0
        self._th_rad = 0.0  # unwrapped
        self._distance_m = 0.0
        self._raw: tuple[int, int, int] | None = None
        self._offset_rad = 0.0

    @property
    def pose(self) -> Pose2:
        """The pose in the odometry frame; yaw in [-pi, pi]."""
        return Pose2(self._x_m, self._y_m, math.remainder(self._th_rad, math.tau))

    @property
    def distance_m(self) -> float:
        """Path length driven, m: the sum of the per-SIP displacement lengths."""
        return self._distance_m

    def restart(self) -> None:
        """Forget the raw reference: the next SIP (a new session) continues the pose."""
        self._raw = None

    def update(self, sip: Sip, params: RobotParams) -> None:
        """Apply one SIP's position counters.

        Args:
            sip: the SIP (``x_counts``/``y_counts`` 15-bit, ``th_counts`` THPOS).
            params: the announced subtype's conversion factors.
        """
        raw = (sip.x_counts, sip.y_counts, sip.th_counts)
        if self._raw is None:
            self._raw = raw
            self._offset_rad = self._th_rad - sip.th_counts * params.angle_rad_per_count
            return
        x0, y0, th0 = self._raw
        self._raw = raw
        m_per_count = params.dist_mm_per_count / 1000.0
        dx_m = position_delta(x0, sip.x_counts) * m_per_count
        dy_m = position_delta(y0, sip.y_counts) * m_per_count
        cos_o, sin_o = math.cos(self._offset_rad), math.sin(self._offset_rad)
        self._x_m += cos_o * dx_m - sin_o * dy_m
        self._y_m += sin_o * dx_m + cos_o * dy_m
        self._th_rad += heading_delta_counts(th0, sip.th_counts) * params.angle_rad_per_count
        self._distance_m += math.hypot(dx_m, dy_m)
