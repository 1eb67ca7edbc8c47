"""The ground-station failsafe: is a GCS still sending HEARTBEATs, and what to do if not.

Rules:

1. A HEARTBEAT of ``type`` MAV_TYPE_GCS from any ground station (that passed the
   signature check) feeds the watchdog. Other vehicles' heartbeats do not.
2. The watchdog arms on the first GCS heartbeat: a robot that never saw a ground
   station has none to lose (ArduPilot behaves the same).
3. ``timeout_ns`` after the last heartbeat the link is LOST, once; the next
   heartbeat REGAINS it.
4. The action on loss depends on the mode (:func:`gcs_lost_action`): MANUAL stops
   (the operator's commands no longer arrive); any other mode does what the
   ``FS_GCS_ACTION`` parameter says ("hold" or "continue").
"""

from __future__ import annotations

from robot.vehicle.app_port import GcsLostAction
from shared.mavlink.modes import Mode


def gcs_lost_action(mode: Mode, configured: str) -> GcsLostAction:
    """The failsafe action in ``mode`` (rule 4).

    Args:
        mode: the robot's mode when the link was lost.
        configured: ``MavlinkConfig.gcs_lost_action``: "hold" or "continue".
    """
    if mode is Mode.MANUAL:
        return "stop"
    return "continue" if configured == "continue" else "hold"


class GcsWatchdog:
    """Times the ground station's heartbeats (module rules 2 and 3).

    Args:
        timeout_ns: silence that counts as a lost link, ns.
    """

    def __init__(self, timeout_ns: int) -> None:
        self.timeout_ns = timeout_ns
        self._last_ns: int | None = None
        self.lost = False
        """The link is lost now."""

    def heartbeat(self, now_ns: int) -> bool:
        """Record a GCS heartbeat at ``now_ns``; True if it regains a lost link."""
        self._last_ns = now_ns
        regained, self.lost = self.lost, False
        return regained

    def get_timer(self) -> int | None:
        """When the link will count as lost, ns; None when unarmed or already lost."""
        if self._last_ns is None or self.lost:
            return None
        return self._last_ns + self.timeout_ns

    def check(self, now_ns: int) -> int | None:
        """Declare the link lost if the timeout passed.

        Returns:
            The silence so far, ns, when the link is lost just now; else None.
        """
        deadline = self.get_timer()
        if deadline is None or now_ns < deadline:
            return None
        self.lost = True
        assert self._last_ns is not None
        return now_ns - self._last_ns
