"""Goal mission items: "drive to key image N" as a MISSION_ITEM_INT.

Encoding (DESIGN.md sec. 4; reference/mavlink-vehicle.md sec. 5, adapted to a
robot that holds one visual memory whose key image ids are unique):

==========  ==================================================================
command     ``MAV_CMD_WAYPOINT_USER_1`` (31000); it exists in common.xml, so
            MAVProxy ``wp load``, MAVSDK ``mission_raw`` and QGC carry it as is
param1      goal key image id, an integer >= 0 (exact in float32 up to 2^24)
param2      reserved: 0 or NaN. Sec. 5 of the reference proposed (param1 =
            memory id, param2 = key index); a sender using that layout gets
            ``MAV_MISSION_INVALID_PARAM2`` instead of a wrong goal
param3      goal image id uploaded over MAVLink FTP (``/goals/<id>.jpg``);
            0 or NaN = none
param4      reserved: 0 or NaN
frame       any; x, y, z are an optional metric hint the robot ignores (a GCS
            draws the item on its map only when it has a location)
==========  ==================================================================

Items run in order: item 0 is the first goal (no ArduPilot-style home at seq 0).
Whether the key image exists in the memory is for the application's validation
hook (``MissionServer(validate=...)``), not for this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.items import MissionItem, MissionRefusal

#: The MAV_CMD of a goal item.
GOAL_COMMAND = mavlink.MAV_CMD_WAYPOINT_USER_1
#: Largest id float32 holds exactly.
MAX_ID = 2**24


@dataclass(frozen=True, slots=True)
class Goal:
    """Drive to a key image of the visual memory."""

    key_image_id: int  #: goal key image id, 0..2^24
    goal_image_id: int = 0  #: FTP-uploaded goal image id; 0 = none

    def __post_init__(self) -> None:
        for name in ("key_image_id", "goal_image_id"):
            value = getattr(self, name)
            if not 0 <= value <= MAX_ID:
                raise ValueError(f"{name} must be in 0..{MAX_ID}, got {value}")

    def to_item(self) -> MissionItem:
        """This goal as a mission item (frame ``MAV_FRAME_MISSION``, no location)."""
        return MissionItem(command=GOAL_COMMAND, frame=mavlink.MAV_FRAME_MISSION,
                           param1=float(self.key_image_id), param3=float(self.goal_image_id))


def _id_param(value: float) -> int | None:
    """An id parameter as an int (NaN reads 0); None if negative, fractional or too big."""
    if math.isnan(value):
        return 0
    if not math.isfinite(value) or value != int(value) or not 0 <= value <= MAX_ID:
        return None
    return int(value)


def _unset(value: float) -> bool:
    return math.isnan(value) or value == 0.0


def goal_from_item(item: MissionItem, seq: int) -> Goal | MissionRefusal:
    """Decode one goal item; ``seq`` only labels the refusal.

    Returns:
        The goal, or a refusal with the most specific MAV_MISSION_RESULT:
        UNSUPPORTED (not a goal command), INVALID_PARAM1 (key image id not an
        integer in range; NaN is refused here since the key is required),
        INVALID_PARAM2/4 (reserved, not 0 or NaN), INVALID_PARAM3 (goal image id).
    """
    if item.command != GOAL_COMMAND:
        name = mavlink.enums["MAV_CMD"].get(item.command)
        label = name.name if name is not None else str(item.command)
        return MissionRefusal(mavlink.MAV_MISSION_UNSUPPORTED,
                              f"item {seq}: command {label} is not a goal "
                              f"(MAV_CMD_WAYPOINT_USER_1, {GOAL_COMMAND})")
    key = None if math.isnan(item.param1) else _id_param(item.param1)
    if key is None:
        return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM1,
                              f"item {seq}: param1 {item.param1} is not a key image id")
    if not _unset(item.param2):
        return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM2,
                              f"item {seq}: param2 {item.param2} is reserved (0)")
    image = _id_param(item.param3)
    if image is None:
        return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM3,
                              f"item {seq}: param3 {item.param3} is not a goal image id")
    if not _unset(item.param4):
        return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM4,
                              f"item {seq}: param4 {item.param4} is reserved (0)")
    return Goal(key_image_id=key, goal_image_id=image)


def goals_from_items(items: tuple[MissionItem, ...]) -> tuple[Goal, ...] | MissionRefusal:
    """Decode a whole mission; the first item that is not a valid goal refuses it."""
    goals = []
    for seq, item in enumerate(items):
        decoded = goal_from_item(item, seq)
        if isinstance(decoded, MissionRefusal):
            return decoded
        goals.append(decoded)
    return tuple(goals)
