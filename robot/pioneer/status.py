"""The driver's view of the robot and the link: link state, status snapshot, counters."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from shared.aria.handshake import RobotIdentity
from shared.interfaces import RangeReading
from shared.pose import Pose2


class LinkState(Enum):
    """Where the client stands with the robot."""

    DISCONNECTED = "DISCONNECTED"  #: no session (before the first open, after a loss)
    CONNECTING = "CONNECTING"  #: handshake, OPEN and CONFIG in progress
    CONNECTED = "CONNECTED"  #: limits pushed and ENABLE sent; SIPs stream
    CLOSED = "CLOSED"  #: closed for good


@dataclass(frozen=True, slots=True)
class PioneerStatus:
    """A snapshot of what the robot reported, SI units.

    Attributes:
        link: the link state.
        identity: the robot's SYNC2 reply on the current or last connection.
        odom_pose: in the odometry frame (where the driver started).
        odom_distance_m: path length driven, m.
        v_m_s: measured forward speed, m/s; 0 unless connected.
        omega_rad_s: measured turn rate, rad/s, counter-clockwise +; 0 unless connected.
        battery_v: battery voltage as last reported, V (0 before the first SIP).
        left_stalled: left wheel stall, as last reported.
        right_stalled: right wheel stall, as last reported.
        front_bumpers: front bumper segments pressed, bit mask, as last reported.
        rear_bumpers: rear bumper segments pressed, bit mask, as last reported.
        estop_pressed: the STOP button, as last reported.
        motors_enabled: connected and the robot reports its motors enabled: velocity
            commands are accepted.
        last_sip_ns: when the last SIP arrived, ns; None before the first.
        ranges: each sonar's latest reading this session, by sonar number (a SIP
            carries only the transducers fired since the previous one).
    """

    link: LinkState
    identity: RobotIdentity | None
    odom_pose: Pose2
    odom_distance_m: float
    v_m_s: float
    omega_rad_s: float
    battery_v: float
    left_stalled: bool
    right_stalled: bool
    front_bumpers: int
    rear_bumpers: int
    estop_pressed: bool
    motors_enabled: bool
    last_sip_ns: int | None
    ranges: tuple[RangeReading, ...] = ()


@dataclass(frozen=True, slots=True)
class LinkCounters:
    """Totals over every session of the run.

    Attributes:
        bad_checksums: received frames that failed their checksum.
        skipped_bytes: received bytes discarded while hunting for a frame header.
        abandoned_frames: partial frames given up after the frame timeout.
        unexpected_packets: well-formed packets that did not fit the conversation.
        sips: SIPs received.
        dropped_commands: velocity commands refused (not connected or motors disabled).
        connects: completed connections.
        link_losses: connections that ended without a CLOSE.
        expired_commands: non-zero velocity commands replaced by zero because the caller
            gave none for ``command_timeout_ns`` (the command watchdog).
    """

    bad_checksums: int = 0
    skipped_bytes: int = 0
    abandoned_frames: int = 0
    unexpected_packets: int = 0
    sips: int = 0
    dropped_commands: int = 0
    connects: int = 0
    link_losses: int = 0
    expired_commands: int = 0
