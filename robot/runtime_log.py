"""What the robot's runtime records as it works (the field log's side of it, and the live
topics')."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from robot.config import VmnavConfig
from robot.mission_run import AppEvent, CycleRecord
from shared.pose import Pose2


class RuntimeLog(Protocol):
    """Where the runtime records what it does (the robot's field log)."""

    def mission_started(self, t_ns: int, goal_id: int, rng_state: Any,
                        config: VmnavConfig) -> None:
        """A mission run to ``goal_id`` starts; ``rng_state`` is its generator's state."""
        ...

    def cycle(self, record: CycleRecord, image: npt.NDArray[np.uint8]) -> None:
        """One mission cycle on its (H, W) uint8 frame."""
        ...

    def event(self, event: AppEvent) -> None:
        """A mission event (transition, key image, localization, lost)."""
        ...

    def teach_frame(self, t_ns: int, image: npt.NDArray[np.uint8], odom_pose: Pose2) -> None:
        """A frame recorded while teaching, with the odometry pose."""
        ...

    def note(self, t_ns: int, level: int, text: str) -> None:
        """Anything else for the operator (``logging`` level, one line)."""
        ...



class RuntimeLogs:
    """Several :class:`RuntimeLog` as one (the field log and the live topics): each call
    goes to every one, in the order given."""

    def __init__(self, *logs: RuntimeLog) -> None:
        self._logs = logs

    def mission_started(self, t_ns: int, goal_id: int, rng_state: Any,
                        config: VmnavConfig) -> None:
        for log in self._logs:
            log.mission_started(t_ns, goal_id, rng_state, config)

    def cycle(self, record: CycleRecord, image: npt.NDArray[np.uint8]) -> None:
        for log in self._logs:
            log.cycle(record, image)

    def event(self, event: AppEvent) -> None:
        for log in self._logs:
            log.event(event)

    def teach_frame(self, t_ns: int, image: npt.NDArray[np.uint8], odom_pose: Pose2) -> None:
        for log in self._logs:
            log.teach_frame(t_ns, image, odom_pose)

    def note(self, t_ns: int, level: int, text: str) -> None:
        for log in self._logs:
            log.note(t_ns, level, text)
