"""Mission progress for the ground station, from successive telemetry snapshots.

Rules:

1. Each poll compares the application's snapshot with the last one reported.
2. A mission item in ``reached_seqs`` not reported yet goes out as
   MISSION_ITEM_REACHED (``MissionServer.item_reached``, which also moves the
   current item on). A run that starts again (``reached_seqs`` no longer holding
   what was reported) starts a fresh record.
3. While the uploaded mission runs (``mission_seq`` not None) the mission server
   follows the application's current item and mission state; a change of current
   item broadcasts MISSION_CURRENT.
4. A change of mission state, a new goal run (``run_count``), or teaching starting
   or stopping, goes out as a STATUSTEXT for people with the application's detail
   line (WARNING for LOST, ABORTED and FAILED, INFO otherwise) and a
   MISSION_CURRENT. The first snapshot only sets the baseline.
5. The same changes send VISUAL_SERVO_STATUS at once, besides its stream: its
   ``state`` carries the outcome of every goal run, photo goals included
   (``ground/mission_watch.py``). A new run already out of its working states when
   first seen (it ended between two polls) is first reported in LOCALIZING, the
   state every run starts in, so a ground station sees each run start before its
   outcome. The final state then stays in the stream until the next run starts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from robot.mission import MissionState
from robot.vehicle.app_port import ACTIVE_STATES, VehicleTelemetry
from robot.vehicle.telemetry import visual_servo_message
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.mission.vehicle import MissionServer

#: (severity, text) -> STATUSTEXT messages.
Notice = Callable[[int, str], list[Message]]

_WARN_STATES = frozenset({MissionState.LOST, MissionState.ABORTED, MissionState.FAILED})


def mission_state_code(state: MissionState) -> int:
    """``MISSION_STATE`` of the uploaded mission while the application runs it:
    ACTIVE on the way, COMPLETE on arrival, PAUSED when stopped before the goal
    (restartable with MISSION_START or AUTO), NOT_STARTED when idle."""
    if state in ACTIVE_STATES:
        return mavlink.MISSION_STATE_ACTIVE
    if state is MissionState.ARRIVED:
        return mavlink.MISSION_STATE_COMPLETE
    if state is MissionState.IDLE:
        return mavlink.MISSION_STATE_NOT_STARTED
    return mavlink.MISSION_STATE_PAUSED


class MissionProgress:
    """Turns telemetry changes into mission messages (module rules).

    Args:
        server: the vehicle's mission server (its current item and state are kept here).
        notice: makes STATUSTEXT messages.
    """

    def __init__(self, server: MissionServer, notice: Notice) -> None:
        self._server = server
        self._notice = notice
        self._reported: list[int] = []
        self._last: tuple[MissionState, bool, int] | None = None

    def update(self, t: VehicleTelemetry, time_usec: int) -> list[Message]:
        """The messages the change from the last snapshot calls for; ``time_usec``: time
        since boot, us."""
        server = self._server
        out: list[Message] = []
        if self._reported != list(t.reached_seqs[:len(self._reported)]):
            self._reported = []
        for seq in t.reached_seqs[len(self._reported):]:
            out += server.item_reached(seq)
            self._reported.append(seq)
        if t.mission_seq is not None:
            server.set_run_state(mission_state_code(t.mission_state))
            if t.mission_seq != server.current_seq and server.set_current(t.mission_seq):
                out.append(server.current_message())
        state = (t.mission_state, t.teaching, t.run_count)
        if self._last is not None and state != self._last:
            out += self._notice(*self._describe(t))
            out.append(server.current_message())
            if t.run_count != self._last[2] and t.mission_state not in ACTIVE_STATES:
                start = replace(t, mission_state=MissionState.LOCALIZING, servo=None)
                out.append(visual_servo_message(start, time_usec))
            out.append(visual_servo_message(t, time_usec))
        self._last = state
        return out

    def _describe(self, t: VehicleTelemetry) -> tuple[int, str]:
        assert self._last is not None
        if t.teaching != self._last[1]:
            return mavlink.MAV_SEVERITY_INFO, "teaching started" if t.teaching else "teaching ended"
        severity = (mavlink.MAV_SEVERITY_WARNING if t.mission_state in _WARN_STATES
                    else mavlink.MAV_SEVERITY_INFO)
        detail = f": {t.mission_detail}" if t.mission_detail else ""
        return severity, f"mission {t.mission_state.value}{detail}"
