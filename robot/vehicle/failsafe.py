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
5. Timed on several clocks at once (a lock-step robot: the link's wall clock and the
   simulation's; each call gives one time per clock, the link's first), the link is
   lost only when it was silent for ``timeout_ns`` on every one: a process starved of
   CPU (the simulation stood still) or a simulation running faster than real time (the
   wall clock hardly moved between the ground's heartbeats) is not a silent ground
   station. A ground station that stopped is silent on both.
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
    """Times the ground station's heartbeats (module rules 2, 3 and 5).

    Args:
        timeout_ns: silence that counts as a lost link, ns.
    """

    def __init__(self, timeout_ns: int) -> None:
        self.timeout_ns = timeout_ns
        self._last_ns: tuple[int, ...] | None = None
        self.lost = False
        """The link is lost now."""

    def heartbeat(self, *now_ns: int) -> bool:
        """Record a GCS heartbeat at ``now_ns`` (one time per clock, rule 5); True if it
        regains a lost link."""
        self._last_ns = now_ns
        regained, self.lost = self.lost, False
        return regained

    def get_timer(self) -> int | None:
        """When the link may count as lost on the first clock, ns (timed on several, it
        may not be lost then: :meth:`check` again later); None when unarmed or already
        lost."""
        if self._last_ns is None or self.lost:
            return None
        return self._last_ns[0] + self.timeout_ns

    def check(self, *now_ns: int) -> int | None:
        """Declare the link lost if the timeout passed on every clock (rule 5).

        Returns:
            The silence so far, ns (the shortest of the clocks'), when the link is lost
            just now; else None.
        """
        if self._last_ns is None or self.lost:
            return None
        silence_ns = min(now - last for now, last in zip(now_ns, self._last_ns, strict=True))
        if silence_ns < self.timeout_ns:
            return None
        self.lost = True
        return silence_ns
