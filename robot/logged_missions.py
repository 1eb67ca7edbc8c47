"""The missions of a robot field log, read back for :func:`robot.replay.replay`.

Reads what :class:`robot.field_log.FieldLog` writes, from the files of one log in time
order (:func:`shared.logs.series.log_series`):

* :data:`~shared.logs.topics.MISSION_START` -> :class:`robot.replay.MissionStart`;
* per cycle, the :data:`~shared.logs.topics.SERVO_STATE`,
  :data:`~shared.logs.topics.BASE_STATE`, :data:`~shared.logs.topics.CMD_VEL` and
  :data:`~shared.logs.topics.CAMERA_IMAGE` messages of one time ->
  :class:`robot.replay.LoggedCycle`.

Messages come in log time order and, at one time, in the order they were logged (the
MCAP reader keeps file order for ties; the files of a series follow each other), so a
mission started on a frame comes before that frame's cycle, and the next goal's
start, made after a cycle on the same frame, after it. A frame at a time with neither
servo nor base state (a teach frame) is no cycle. Frames are decoded one cycle at a
time, so a long log needs the memory of one frame.

Bad input raises :class:`~shared.errors.InputError` naming the file and the time.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robot.config import config_from_log
from robot.replay import LoggedCycle, MissionStart, generator_from_state, logged_fields
from shared.errors import InputError
from shared.interfaces import BaseState, Blocked, RangeReading
from shared.logs import topics
from shared.logs.messages import image_from_compressed
from shared.logs.reader import LogMessage, log_info, read_messages
from shared.logs.series import series_name
from shared.pose import Pose2

#: The topics replay reads.
REPLAY_TOPICS = (topics.MISSION_START, topics.SERVO_STATE, topics.BASE_STATE, topics.CMD_VEL,
                 topics.CAMERA_IMAGE)
#: The parts of a cycle, by topic.
_PARTS = {topics.SERVO_STATE: "servo", topics.BASE_STATE: "base", topics.CMD_VEL: "command",
          topics.CAMERA_IMAGE: "image"}


def check_replay_log(files: Sequence[Path]) -> None:
    """Check that the log's ``files`` hold mission starts and mission cycles.

    Raises:
        InputError: naming the log: a file missing, not MCAP or unfinished, or no
            message on :data:`~shared.logs.topics.MISSION_START`, or on both of
            :data:`~shared.logs.topics.SERVO_STATE` and :data:`~shared.logs.topics.BASE_STATE`.
    """
    counts: dict[str, int] = {}
    for file in files:
        for t in log_info(file).topics:
            counts[t.topic] = counts.get(t.topic, 0) + t.message_count
    if not counts.get(topics.MISSION_START):
        raise InputError(series_name(files), f"no mission start (no messages on "
                         f"{topics.MISSION_START}): replay needs a robot field log of missions")
    if not (counts.get(topics.SERVO_STATE) and counts.get(topics.BASE_STATE)):
        raise InputError(series_name(files), f"no mission cycles (no messages on "
                         f"{topics.SERVO_STATE} and {topics.BASE_STATE})")


def read_mission_starts(files: Sequence[Path]) -> list[MissionStart]:
    """The log's mission starts, in time order.

    Raises:
        InputError: a file cannot be read, or a mission start is malformed.
    """
    return [mission_start(file, message) for file in files
            for message in read_messages(file, [topics.MISSION_START])]


def read_missions(files: Sequence[Path]) -> Iterator[MissionStart | LoggedCycle]:
    """The log's mission starts and cycles in the order they happened (module docstring).

    Raises:
        InputError: a file cannot be read (damaged, unfinished), or a message is malformed.
    """
    cycle: _Cycle | None = None
    for file in files:
        for message in read_messages(file, REPLAY_TOPICS):
            part = _PARTS.get(message.topic)
            if cycle is not None and (part is None or message.clock_ns != cycle.t_ns
                                      or part in cycle.parts):
                if (logged := cycle.logged()) is not None:
                    yield logged
                cycle = None
            if part is None:
                yield mission_start(file, message)
                continue
            if cycle is None:
                cycle = _Cycle(file, message.clock_ns, {})
            cycle.parts[part] = message.data
    if cycle is not None and (logged := cycle.logged()) is not None:
        yield logged


def mission_start(file: Path, message: LogMessage) -> MissionStart:
    """The :class:`robot.replay.MissionStart` of a ``vmnav.MissionStart`` message of ``file``
    (its config in either layout, :func:`robot.config.config_from_log`).

    Raises:
        InputError: a field missing or malformed (``ConfigError`` for the config).
    """
    t_ns = message.clock_ns
    where = f"{file}: mission start at {t_ns / 1e9:.3f} s"
    data = message.data
    missing = [k for k in ("goal_key_image_id", "rng_state", "config") if k not in data]
    if missing:
        raise InputError(where, f"no {missing[0]!r} field")
    goal = data["goal_key_image_id"]
    if not isinstance(goal, int) or isinstance(goal, bool):
        raise InputError(where, f"goal_key_image_id must be an integer, got {goal!r}")
    config = config_from_log(data["config"], where, "config")
    try:
        generator_from_state(data["rng_state"])
    except InputError as e:
        raise InputError(where, str(e)) from None
    return MissionStart(t_ns, goal, data["rng_state"], config)


def base_state(where: str, data: Mapping[str, Any]) -> BaseState:
    """The :class:`~shared.interfaces.BaseState` of a ``vmnav.BaseState`` message (null
    battery: NaN).

    Raises:
        InputError: at ``where``: a field missing or malformed.
    """
    try:
        battery = data["battery_v"]
        cause, distance = data.get("blocked_cause"), data.get("blocked_distance_m")
        blocked = None if cause is None else Blocked(
            str(cause), math.nan if distance is None else float(distance),
            int(data["blocked_since_ns"]))
        ranges = tuple(
            RangeReading(int(r["sensor"]), Pose2(float(r["sensor_x_m"]), float(r["sensor_y_m"]),
                                                 float(r["sensor_heading_rad"])),
                         float(r["range_m"]), int(r["stamp_ns"]),
                         Pose2(float(r["odom_x_m"]), float(r["odom_y_m"]),
                               float(r["odom_yaw_rad"])))
            for r in data.get("ranges", ()))
        return BaseState(Pose2(float(data["x_m"]), float(data["y_m"]), float(data["yaw_rad"])),
                         float(data["odom_distance_m"]), bool(data["bumped"]),
                         bool(data["stalled"]), math.nan if battery is None else float(battery),
                         bool(data["motors_enabled"]), ranges=ranges, blocked=blocked,
                         bumped_rear_only=bool(data.get("bumped_rear_only", False)))
    except KeyError as e:
        raise InputError(where, f"base state without {e}") from None
    except (TypeError, ValueError) as e:
        raise InputError(where, f"malformed base state ({e})") from None


@dataclass
class _Cycle:
    """The messages of one time, by part (servo, base, command, image)."""

    file: Path
    t_ns: int
    parts: dict[str, dict[str, Any]]

    def logged(self) -> LoggedCycle | None:
        """The cycle; None when these are no cycle's messages (a teach frame)."""
        parts = self.parts
        if "servo" not in parts and "base" not in parts:
            return None
        where = f"{self.file}: cycle at {self.t_ns / 1e9:.3f} s"
        image, fmt = None, ""
        if "image" in parts:
            try:
                image, fmt = image_from_compressed(parts["image"])
            except ValueError as e:
                raise InputError(f"{where}: camera frame", str(e)) from None
        return LoggedCycle(
            t_ns=self.t_ns,
            base=base_state(where, parts["base"]) if "base" in parts else None,
            image=image, lossless=fmt == "png",
            logged=logged_fields(parts["servo"], parts.get("command")) if "servo" in parts
            else None)
