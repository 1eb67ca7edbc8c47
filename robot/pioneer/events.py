"""What the Pioneer driver reports, as typed events for telemetry and logs.

The sans-I/O :class:`~robot.pioneer.client.PioneerClient` produces the link and robot
events; the :class:`~robot.pioneer.driver.PioneerDriver` adds the transport ones
(:class:`Reconnecting`, :class:`TransportFailed`). Expected outcomes such as a lost
link are events, never exceptions (DESIGN.md sec. 4, "Errors").
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.aria.config_packet import ConfigPacket
from shared.aria.handshake import RobotIdentity


@dataclass(frozen=True, slots=True)
class Connected:
    """Handshake done, motion limits pushed, ENABLE 1 sent: commands are accepted once
    the robot reports its motors enabled.

    Attributes:
        identity: the robot's SYNC2 reply (name, class, subclass).
        config: its CONFIG reply, or None if none came within the configured wait.
    """

    identity: RobotIdentity
    config: ConfigPacket | None

    def __str__(self) -> str:
        i = self.identity
        reply = "no CONFIG reply" if self.config is None else "CONFIG received"
        return f"connected to {i.name!r} ({i.robot_class} {i.subclass}), {reply}"


@dataclass(frozen=True, slots=True)
class ConnectFailed:
    """No complete handshake after the configured SYNC0 attempts.

    Attributes:
        attempts: SYNC0 packets sent on this transport.
    """

    attempts: int


@dataclass(frozen=True, slots=True)
class LinkLost:
    """The connection ended without a CLOSE: no SIP for the link timeout, the transport
    went away, or the robot announced a reset. Motion is treated as stopped.

    Attributes:
        reason: what happened, with values and units.
    """

    reason: str


@dataclass(frozen=True, slots=True)
class StaleStream:
    """SIPs arrived during the handshake: a previous connection was never closed. CLOSE
    was sent and the handshake restarted (ARIA's recovery, reference §3)."""


@dataclass(frozen=True, slots=True)
class UnknownSubtype:
    """The robot announced a subclass without known conversion factors.

    Attributes:
        subclass: what the robot announced.
        assumed: the subtype whose factors are used instead.
    """

    subclass: str
    assumed: str


@dataclass(frozen=True, slots=True)
class EStopPressed:
    """The robot reports its STOP button pressed (SIP FLAGS bit 5); motion is refused."""


@dataclass(frozen=True, slots=True)
class EStopReleased:
    """The STOP button is released; the motors stay disabled until re-enabled."""


@dataclass(frozen=True, slots=True)
class MotorsEnabled:
    """The robot reports its motors enabled (SIP FLAGS bit 0)."""


@dataclass(frozen=True, slots=True)
class MotorsDisabled:
    """The robot reports its motors disabled; the commanded velocity was reset to zero."""


@dataclass(frozen=True, slots=True)
class CommandExpired:
    """The command watchdog fired: no velocity command came for ``limit_ns``, so the last
    non-zero one was replaced by zero (VEL 0, RVEL 0 sent) until the next command.

    Attributes:
        age_ns: how old the command was when it expired, ns.
        limit_ns: the limit, ``PioneerDriverConfig.command_timeout_ns``, ns.
    """

    age_ns: int
    limit_ns: int

    def __str__(self) -> str:
        return (f"no velocity command for {self.age_ns / 1e9:.2f} s (limit "
                f"{self.limit_ns / 1e9:.2f} s): stopped until the next command")


@dataclass(frozen=True, slots=True)
class LinkNoise:
    """Corrupt or unexpected input since the last report (at most one report per period).

    Attributes:
        bad_checksums: frames that failed their checksum.
        skipped_bytes: bytes discarded while hunting for a frame header.
        abandoned_frames: partial frames given up after the frame timeout.
        unexpected_packets: well-formed packets that did not fit the conversation.
    """

    bad_checksums: int
    skipped_bytes: int
    abandoned_frames: int
    unexpected_packets: int


@dataclass(frozen=True, slots=True)
class Reconnecting:
    """The driver will re-open the transport.

    Attributes:
        attempt: failed connections in a row so far (1 for the first retry).
        delay_ns: wait before the attempt, ns.
    """

    attempt: int
    delay_ns: int


@dataclass(frozen=True, slots=True)
class TransportFailed:
    """Opening the transport failed.

    Attributes:
        where: the transport (a pyserial URL).
        problem: the reason.
    """

    where: str
    problem: str


@dataclass(frozen=True, slots=True)
class Closed:
    """The driver closed: stop and CLOSE were sent if the link was open."""


PioneerEvent = (
    Connected | ConnectFailed | LinkLost | StaleStream | UnknownSubtype | EStopPressed
    | EStopReleased | MotorsEnabled | MotorsDisabled | CommandExpired | LinkNoise | Reconnecting
    | TransportFailed | Closed
)
"""Everything the client and the driver report."""
