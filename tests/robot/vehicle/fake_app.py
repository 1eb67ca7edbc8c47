"""FakeApp: the application side of the vehicle endpoint, for tests.

It stands in for the robot application (which implements ``VehicleApp`` later): it
records every call, keeps a telemetry snapshot the test edits, and behaves like a
robot would in the few ways the endpoint can observe (a mode set is the mode
reported; a mission started is AUTO and localizing).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from robot.config import VmnavConfig
from robot.mission import MissionState
from robot.vehicle.app_port import GcsLostAction, JobOutcome, VehicleTelemetry
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.mission.items import MissionRefusal
from shared.mavlink.modes import Mode


class FakeApp:
    """A recording :class:`~robot.vehicle.app_port.VehicleApp`.

    Args:
        known_keys: key images its memory holds.
        unreachable: key images no route reaches.
    """

    def __init__(self, known_keys: Iterable[int] = range(7),
                 unreachable: Iterable[int] = ()) -> None:
        self.known_keys = frozenset(known_keys)
        self.unreachable = frozenset(unreachable)
        self.state = VehicleTelemetry(mode=Mode.MANUAL, armed=True, battery_v=12.6)
        self.calls: list[tuple[Any, ...]] = []
        self.configs: list[VmnavConfig] = []
        self.accept = True  # what requests return
        self.notices: list[tuple[int, str]] = []  # what next_notice hands out, oldest first
        self.job_outcomes: list[JobOutcome] = []  # what next_job_outcome hands out
        self.stored_path: int | None = 1  # the path teach_stop stores (None: not stored)

    def update(self, **changes: Any) -> None:
        """Change the telemetry snapshot."""
        self.state = dataclasses.replace(self.state, **changes)

    def called(self, name: str) -> list[tuple[Any, ...]]:
        """The arguments of every call of ``name``, in order."""
        return [call[1:] for call in self.calls if call[0] == name]

    # -- VehicleApp ---------------------------------------------------------------------

    def telemetry(self) -> VehicleTelemetry:
        return self.state

    def validate_goals(self, goals: tuple[Goal, ...]) -> MissionRefusal | None:
        self.calls.append(("validate_goals", goals))
        for seq, goal in enumerate(goals):
            if goal.key_image_id not in self.known_keys:
                return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM1,
                                      f"item {seq}: no key image {goal.key_image_id}")
            if goal.key_image_id in self.unreachable:
                return MissionRefusal(mavlink.MAV_MISSION_DENIED,
                                      f"item {seq}: no route to key image {goal.key_image_id}")
        return None

    def set_mode(self, mode: Mode) -> bool:
        self.calls.append(("set_mode", mode))
        if self.accept:
            self.update(mode=mode)
        return self.accept

    def arm(self, armed: bool, force: bool) -> bool:
        self.calls.append(("arm", armed, force))
        return self.accept

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        self.calls.append(("start_mission", goals, first_seq))
        if self.accept:
            self.update(mode=Mode.AUTO, mission_state=MissionState.LOCALIZING,
                        mission_detail="localizing the start", mission_seq=first_seq,
                        reached_seqs=(), goal_key=goals[-1].key_image_id)
        return self.accept

    def goto_image(self, path: Path) -> bool:
        self.calls.append(("goto_image", path, path.read_bytes()))
        return self.accept

    def params_changed(self, config: VmnavConfig) -> None:
        self.configs.append(config)

    def manual_control(self, x: float, y: float, z: float, r: float, buttons: int,
                       now_ns: int) -> None:
        self.calls.append(("manual_control", x, y, z, r, buttons, now_ns))

    def teach_start(self, name: str) -> bool:
        self.calls.append(("teach_start", name))
        return self.accept

    def teach_stop(self) -> bool:
        """Accepted: stores path ``stored_path`` at once (None: too short), as the robot's
        worker would, with its notice."""
        self.calls.append(("teach_stop",))
        if self.accept:
            text = (f"path {self.stored_path} 'corridor': 12 key images, 0 junction(s)"
                    if self.stored_path is not None else
                    "teach 'corridor': 0.12 m driven, a path needs 1.00 m: nothing stored")
            self.notices.append((logging.INFO, text))
            self.job_outcomes.append(JobOutcome("path", self.stored_path, text))
        return self.accept

    def gcs_lost(self, action: GcsLostAction) -> None:
        self.calls.append(("gcs_lost", action))
        if action == "hold":
            self.update(mode=Mode.HOLD)

    def gcs_regained(self) -> None:
        self.calls.append(("gcs_regained",))

    def next_notice(self) -> tuple[int, str] | None:
        return self.notices.pop(0) if self.notices else None

    def next_job_outcome(self) -> JobOutcome | None:
        return self.job_outcomes.pop(0) if self.job_outcomes else None
