"""Whether a goal run reached its goal, from the vehicle's structured messages (pure).

Rules (the vehicle's side: ``robot/vehicle/progress.py`` and ``telemetry.py``):

1. The outcome travels in VISUAL_SERVO_STATUS ``state`` (``VTR_STATE``): ARRIVED
   is reached; ABORTED and FAILED are stopped short. The vehicle keeps the last
   run's final state there, streamed, until the next run starts, so a final state
   counts only after the watch saw a run working on the goal (LOCALIZING,
   FOLLOWING or LOST): the one left from an earlier run does not. The vehicle
   sends VISUAL_SERVO_STATUS at every change of state and reports each new run in
   LOCALIZING first, so no run ends unseen.
2. An uploaded mission (``last_seq`` not None) is also reached by
   MISSION_ITEM_REACHED for its last item, or by MISSION_CURRENT
   ``mission_state`` COMPLETE after ACTIVE; PAUSED after ACTIVE (stopped before the
   goal: aborted, failed, or switched to HOLD) is stopped short.
3. A photo goal (no mission item) ends by rule 1 alone.
4. STATUSTEXT is for people: the watch does not read it.
"""

from __future__ import annotations

from typing import Any

from shared.mavlink.dialect import mavlink

#: VISUAL_SERVO_STATUS states of a run working on its goal.
WORKING_STATES = frozenset({mavlink.VTR_STATE_LOCALIZING, mavlink.VTR_STATE_FOLLOWING,
                            mavlink.VTR_STATE_LOST})
#: Final VISUAL_SERVO_STATUS states -> reached.
FINAL_STATES = {mavlink.VTR_STATE_ARRIVED: True, mavlink.VTR_STATE_ABORTED: False,
                mavlink.VTR_STATE_FAILED: False}


class MissionWatch:
    """Follows one goal run (module rules).

    Args:
        last_seq: seq of the mission's last item; None for a photo goal.
    """

    def __init__(self, last_seq: int | None) -> None:
        self.last_seq = last_seq
        self.outcome: bool | None = None
        """True once reached, False once stopped short; None while running."""
        self._working = False
        self._active = False

    def handle_message(self, msg: Any) -> None:
        """Feed one message from the vehicle."""
        if self.outcome is not None:
            return
        kind = msg.get_type()
        if kind == "VISUAL_SERVO_STATUS":
            if msg.state in WORKING_STATES:
                self._working = True
            elif self._working and msg.state in FINAL_STATES:
                self.outcome = FINAL_STATES[msg.state]
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
