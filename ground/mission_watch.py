"""Whether a goal run reached its goal, from the vehicle's messages (pure).

Rules (the vehicle's side: ``robot/vehicle/progress.py``):

1. Reached: MISSION_ITEM_REACHED for the last item of the mission; or
   MISSION_CURRENT ``mission_state`` COMPLETE after it was ACTIVE (a COMPLETE left
   from an earlier run does not count); or a STATUSTEXT ``mission arrived...``.
2. Not reached: MISSION_CURRENT PAUSED after ACTIVE (stopped before the goal:
   aborted, failed, or switched to HOLD), or a STATUSTEXT ``mission aborted...`` /
   ``mission failed...``.
3. A photo goal (no mission item) ends only by rule 1's and 2's STATUSTEXTs: the
   vehicle reports no mission state for it.
"""

from __future__ import annotations

from typing import Any

from shared.mavlink.dialect import mavlink

#: STATUSTEXT prefixes of the final mission states (robot.mission.MissionState values).
ARRIVED_TEXT = "mission arrived"
STOPPED_TEXTS = ("mission aborted", "mission failed")


class MissionWatch:
    """Follows one goal run (module rules).

    Args:
        last_seq: seq of the mission's last item; None for a photo goal.
    """

    def __init__(self, last_seq: int | None) -> None:
        self.last_seq = last_seq
        self.outcome: bool | None = None
        """True once reached, False once stopped short; None while running."""
        self._active = False

    def handle_message(self, msg: Any) -> None:
        """Feed one message from the vehicle."""
        if self.outcome is not None:
            return
        kind = msg.get_type()
        if kind == "STATUSTEXT":
            if msg.text.startswith(ARRIVED_TEXT):
                self.outcome = True
            elif msg.text.startswith(STOPPED_TEXTS):
                self.outcome = False
        elif self.last_seq is None:
            return
        elif kind == "MISSION_ITEM_REACHED" and msg.seq == self.last_seq:
            self.outcome = True
        elif kind == "MISSION_CURRENT":
            state = getattr(msg, "mission_state", mavlink.MISSION_STATE_UNKNOWN)
            if state == mavlink.MISSION_STATE_ACTIVE:
                self._active = True
            elif self._active and state == mavlink.MISSION_STATE_COMPLETE:
                self.outcome = True
            elif self._active and state == mavlink.MISSION_STATE_PAUSED:
                self.outcome = False
