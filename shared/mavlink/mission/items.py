"""Mission items as the mission protocol carries them, independent of their meaning.

A :class:`MissionItem` is a MISSION_ITEM_INT without its addressing, ``seq``,
``current`` flag and ``mission_type``: what the vehicle stores. Its float fields
are rounded to float32 on construction, as the wire does, so an item survives an
upload and download unchanged (``==``). What a command means (our goal items)
lives in ``goal.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

from shared.mavlink.address import Address
from shared.mavlink.dialect import mavlink, to_float32

#: Frames whose MISSION_ITEM x/y are degrees (sent as degrees * 1e7 in MISSION_ITEM_INT).
_GLOBAL_FRAMES = frozenset({
    mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    mavlink.MAV_FRAME_GLOBAL_INT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT, mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
})


@dataclass(frozen=True, slots=True)
class MissionItem:
    """One stored mission item (the payload of MISSION_ITEM_INT).

    ``x`` and ``y`` are MISSION_ITEM_INT's integers: degrees * 1e7 in global frames,
    metres * 1e4 in local frames, raw integers in ``MAV_FRAME_MISSION``.
    """

    command: int  #: a MAV_CMD
    frame: int = mavlink.MAV_FRAME_MISSION  #: a MAV_FRAME
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0
    y: int = 0
    z: float = 0.0
    autocontinue: bool = True

    def __post_init__(self) -> None:
        for name in ("param1", "param2", "param3", "param4", "z"):
            object.__setattr__(self, name, to_float32(getattr(self, name)))

    def to_message(self, seq: int, target: Address, current: bool = False,
                   ) -> mavlink.MAVLink_mission_item_int_message:
        """This item as MISSION_ITEM_INT number ``seq`` of the mission (mission_type 0)."""
        return mavlink.MAVLink_mission_item_int_message(
            target.system_id, target.component_id, seq, self.frame, self.command,
            int(current), int(self.autocontinue), self.param1, self.param2, self.param3,
            self.param4, self.x, self.y, self.z, mavlink.MAV_MISSION_TYPE_MISSION)


def item_from_message(
    msg: mavlink.MAVLink_mission_item_int_message | mavlink.MAVLink_mission_item_message,
) -> MissionItem:
    """The item a MISSION_ITEM_INT carries, or a deprecated MISSION_ITEM (float x/y,
    converted to MISSION_ITEM_INT's integer scaling for its frame)."""
    x, y = msg.x, msg.y
    if isinstance(msg, mavlink.MAVLink_mission_item_message):
        scale = 1e7 if msg.frame in _GLOBAL_FRAMES else (
            1.0 if msg.frame == mavlink.MAV_FRAME_MISSION else 1e4)
        x, y = round(msg.x * scale), round(msg.y * scale)
    return MissionItem(command=msg.command, frame=msg.frame, param1=msg.param1,
                       param2=msg.param2, param3=msg.param3, param4=msg.param4,
                       x=int(x), y=int(y), z=msg.z, autocontinue=bool(msg.autocontinue))


@dataclass(frozen=True, slots=True)
class MissionRefusal:
    """Why the vehicle will not take a mission: the MISSION_ACK result and a sentence."""

    result: int  #: a MAV_MISSION_RESULT other than ACCEPTED, e.g. MAV_MISSION_INVALID_PARAM1
    reason: str  #: for the operator (STATUSTEXT) and logs, e.g. "item 2: no key image 99"


def mission_result_name(result: int) -> str:
    """``MAV_MISSION_RESULT`` name for ``result``, e.g. ``"MAV_MISSION_INVALID_PARAM1"``."""
    entry = mavlink.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT({result})"
