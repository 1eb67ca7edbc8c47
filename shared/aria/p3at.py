"""The Pioneer 3-AT-SH as ARIA knows it: subclass, conversion factors, sonar geometry.

Values from ARIA's ``params/p3at-sh.p`` and ``ArRobotTypes.cpp:1544`` (aria-protocol.md
§8). The subclass and the position unit go together: announcing ``p3at-sh`` makes
ARIA read XPOS/YPOS with DistConvFactor 1.0 mm per count (``p3at`` would mean 0.465).
"""

from __future__ import annotations

import math

from shared.pose import Pose2

SUBCLASS = "p3at-sh"
"""The SYNC2 subclass; ARIA loads ``params/p3at-sh.p``."""
ROBOT_CLASS = "Pioneer"

DIST_CONV_M = 0.001
"""DistConvFactor: metres per XPOS/YPOS count (1.0 mm)."""
ANGLE_CONV_RAD = 0.001534
"""AngleConvFactor: radians per THPOS unit (about 2 pi / 4096)."""
THPOS_UNITS_PER_TURN = 4096
"""THPOS wraps to -2048..2047 (MobileSim's convention)."""
DIFF_CONV_RAD_PER_M = 3.4
"""DiffConvFactor, per metre: omega (rad/s) = (right - left) (m/s) / 2 * this (0.0034 per mm)."""
VEL2_DIVISOR_M_S = 0.020
"""Vel2Divisor: VEL2 wheel bytes are in units of 20 mm/s."""

FRONT_BUMPER_SEGMENTS = 0x1F
"""The five front bumper segments, as SIP bits; a bump sets them all (the body reports
front/rear contact, not which segment)."""
REAR_BUMPER_SEGMENTS = 0x1F
"""The five rear bumper segments."""

SONAR_POSES: tuple[Pose2, ...] = tuple(
    Pose2(x_mm / 1000, y_mm / 1000, math.radians(th_deg))
    for x_mm, y_mm, th_deg in (
        (147, 136, 90), (193, 119, 50), (227, 79, 30), (245, 27, 10),
        (245, -27, -10), (227, -79, -30), (193, -119, -50), (147, -136, -90),
        (-144, -136, -90), (-189, -119, -130), (-223, -79, -150), (-241, -27, -170),
        (-241, 27, 170), (-223, 79, 150), (-189, 119, 130), (-144, 136, 90),
    )
)
"""Sonar k's (x_m, y_m, heading_rad) in the robot frame (x forward, y left); 0-7 are the
front array (left to right), 8-15 the rear array (right to left)."""
SONARS_PER_ARRAY = 8
