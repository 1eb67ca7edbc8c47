"""The three interfaces the robot application talks through (issue 4, item 1).

* :class:`FrameSource`: camera frames, ``(t_ns, grey H x W uint8)``;
* :class:`MobileBase`: velocity commands out; odometry, safety and power state in;
* :class:`shared.clock.Clock`: time as integer ns, and waiting for a deadline.

The simulator provides all three in lock-step, the ARIA driver and a real camera
on the robot. Units are SI (m, rad, s, V); wire units stop in the adapters.
Frames: the robot frame has x forward, y left, z up, yaw counter-clockwise; the
odometry frame is wherever the base's odometry started (DESIGN.md sec. 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from shared.clock import Clock
from shared.pose import Pose2

__all__ = ["BaseState", "Blocked", "Clock", "FrameSource", "MobileBase", "RangeReading"]


@runtime_checkable
class FrameSource(Protocol):
    """Anything that yields grey camera frames (DESIGN.md sec. 4, "Frame sources")."""

    def read(self) -> tuple[int, npt.NDArray[np.uint8]] | None:
        """The next frame.

        Returns:
            ``(t_ns, image)``: the exposure time on the application's clock, ns, and a
            (H, W) uint8 grey image; None when no frame will come (end of a file,
            camera closed).
        """
        ...


@dataclass(frozen=True, slots=True)
class RangeReading:
    """The latest echo of one range sensor of the base (a sonar transducer).

    Attributes:
        sensor: the sensor's number on the base (P3-AT: 0-7 front array, 8-15 rear).
        sensor_pose: the sensor in the robot frame: x_m, y_m and the heading of its axis,
            rad, counter-clockwise from the robot's x axis.
        range_m: distance along the axis to the nearest echo, m; the sensor's maximum
            range when nothing echoed.
        t_ns: when the reading arrived, ns, on the application's clock.
        odom_pose: the robot frame's pose in the odometry frame when it arrived (the
            echo stays where it was in the odometry frame while the robot moves on).
    """

    sensor: int
    sensor_pose: Pose2
    range_m: float
    t_ns: int
    odom_pose: Pose2


#: Why the safety layer holds the robot (:attr:`Blocked.cause`).
BLOCK_CAUSES = ("obstacle", "sonar_silent", "pushed", "bumper", "e_stop")


@dataclass(frozen=True, slots=True)
class Blocked:
    """The safety layer (``robot.safety``) holds the robot's forward motion.

    Attributes:
        cause: one of :data:`BLOCK_CAUSES`: an echo in the robot's way ("obstacle"),
            front sonars whose readings went stale ("sonar_silent"), a bumper pressed
            while the robot stood still (someone walked into it: "pushed"), a bumper
            hit while it moved (held until the operator re-arms or changes mode), the
            operator's emergency stop (held likewise).
        distance_m: for "obstacle", the echo's distance ahead of the robot's front, m;
            NaN otherwise.
        since_ns: when the hold began, ns.
    """

    cause: str
    distance_m: float
    since_ns: int

    def __post_init__(self) -> None:
        if self.cause not in BLOCK_CAUSES:
            raise ValueError(f"Blocked: cause must be one of {', '.join(BLOCK_CAUSES)}, "
                             f"got {self.cause!r}")

    def describe(self) -> str:
        """One line for the operator, e.g. ``obstacle 0.45 m ahead``."""
        if self.cause == "obstacle":
            return f"obstacle {self.distance_m:.2f} m ahead"
        return {"sonar_silent": "front sonars silent", "bumper": "bumper pressed",
                "pushed": "someone walked into the robot", "e_stop": "emergency stop"}[self.cause]


@dataclass(frozen=True, slots=True)
class BaseState:
    """What the mobile base reports.

    Attributes:
        odom_pose: the robot frame's pose in the odometry frame.
        odom_distance_m: distance driven since the odometry started, m, >= 0 (sums
            |forward motion|, so it grows when reversing too).
        bumped: a bumper is pressed now.
        stalled: a motor is stalled now.
        battery_v: battery voltage, V.
        motors_enabled: the motors accept velocity commands.
        reporting: the base's reports are current (for a Pioneer: connected, and its
            last SIP is recent); False means the fields above are stale and commands
            may not arrive.
        ranges: the latest reading of each range sensor, by sensor number (empty for a
            base without any).
        blocked: set by the safety layer's base (``robot.safe_base.SafeBase``) while it
            holds the robot's forward motion; None when the way is clear (and always
            from a bare base).
        bumped_rear_only: the bumpers pressed now are all at the rear (``bumped`` too): a
            robot driving forward did not hit anything with them. False where the base
            cannot tell its front bumper from its rear one.
    """

    odom_pose: Pose2
    odom_distance_m: float
    bumped: bool
    stalled: bool
    battery_v: float
    motors_enabled: bool
    reporting: bool = True
    ranges: tuple[RangeReading, ...] = ()
    blocked: Blocked | None = None
    bumped_rear_only: bool = False

    def __post_init__(self) -> None:
        if len(self.odom_pose) != 3 or not all(math.isfinite(v) for v in self.odom_pose):
            raise ValueError(f"BaseState: odom_pose must be 3 finite numbers (x_m, y_m, "
                             f"yaw_rad), got {self.odom_pose!r}")
        if not (math.isfinite(self.odom_distance_m) and self.odom_distance_m >= 0):
            raise ValueError(f"BaseState: odom_distance_m must be finite and >= 0, got "
                             f"{self.odom_distance_m}")
        if self.bumped_rear_only and not self.bumped:
            raise ValueError("BaseState: bumped_rear_only needs bumped")


@runtime_checkable
class MobileBase(Protocol):
    """A differential or skid-steer base driven by velocity commands."""

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Drive at a forward speed and turn rate (robot frame) until the next command.

        A base with a command watchdog (the Pioneer driver: ``[pioneer]
        command_timeout_ns``) stops a command older than its limit, so a caller repeats
        its command at its loop's rate for as long as the robot should move.

        Args:
            v_m_s: forward speed, m/s (negative reverses).
            omega_rad_s: turn rate about z, counter-clockwise positive, rad/s.
        """
        ...

    def stop(self) -> None:
        """Command zero velocity."""
        ...

    def state(self) -> BaseState:
        """The latest state the base reported."""
        ...
