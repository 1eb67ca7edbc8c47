"""Mission items as the mission protocol carries them, independent of their meaning.

A :class:`MissionItem` is a MISSION_ITEM_INT without its addressing, ``seq``,
``current`` flag and ``mission_type``: what the vehicle stores. Its float fields
are rounded to float32 on construction, as the wire does, so an item survives an
upload and download unchanged (``==``). What a command means (our goal items)
lives in ``goal.py``.

Received items are checked before they become a :class:`MissionItem`
(:func:`item_from_message`): the frame must be a MAV_FRAME (reserved numbers and
ENUM_END are refused), and a deprecated MISSION_ITEM's float x/y must be finite and
fit MISSION_ITEM_INT's int32 once scaled for its frame (a latitude of 1000 deg does
not; the vehicle could not send it back).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.mavlink.address import Address
from shared.mavlink.dialect import mavlink, to_float32

#: Frames whose MISSION_ITEM x/y are degrees (sent as degrees * 1e7 in MISSION_ITEM_INT).
_GLOBAL_FRAMES = frozenset({
    mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    mavlink.MAV_FRAME_GLOBAL_INT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT, mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT,
})
#: The MAV_FRAMEs an item may name: common.xml's, without its reserved numbers and ENUM_END.
KNOWN_FRAMES = frozenset(
    value for value, entry in mavlink.enums["MAV_FRAME"].items()
    if "_RESERVED_" not in entry.name and not entry.name.endswith("_ENUM_END"))
_INT32_MIN, _INT32_MAX = -2**31, 2**31 - 1


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
) -> MissionItem | MissionRefusal:
    """The item a MISSION_ITEM_INT carries, or a deprecated MISSION_ITEM (float x/y,
    converted to MISSION_ITEM_INT's integer scaling for its frame: degrees * 1e7 in a
    global frame, metres * 1e4 in a local one, as is in ``MAV_FRAME_MISSION``).

    Returns:
        The item, or why it cannot be one (module docstring), labelled with
        ``msg.seq``: MAV_MISSION_UNSUPPORTED_FRAME for an unknown frame,
        MAV_MISSION_INVALID_PARAM5_X / PARAM6_Y for a MISSION_ITEM x / y that is not
        finite or out of int32 range once scaled.
    """
    if msg.frame not in KNOWN_FRAMES:
        return MissionRefusal(mavlink.MAV_MISSION_UNSUPPORTED_FRAME,
                              f"item {msg.seq}: frame {msg.frame} is not a MAV_FRAME")
    x, y = msg.x, msg.y
    if isinstance(msg, mavlink.MAVLink_mission_item_message):
        scale = 1e7 if msg.frame in _GLOBAL_FRAMES else (
            1.0 if msg.frame == mavlink.MAV_FRAME_MISSION else 1e4)
        x, y = _scaled(msg.x, scale), _scaled(msg.y, scale)
        if x is None:
            return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM5_X,
                                  f"item {msg.seq}: x {msg.x} out of range in frame {msg.frame}")
        if y is None:
            return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM6_Y,
                                  f"item {msg.seq}: y {msg.y} out of range in frame {msg.frame}")
    return MissionItem(command=msg.command, frame=msg.frame, param1=msg.param1,
                       param2=msg.param2, param3=msg.param3, param4=msg.param4,
                       x=int(x), y=int(y), z=msg.z, autocontinue=bool(msg.autocontinue))


def _scaled(value: float, scale: float) -> int | None:
    """``value * scale`` rounded, or None if not finite or outside int32."""
    product = value * scale
    if not math.isfinite(product):
        return None
    scaled = round(product)
    return scaled if _INT32_MIN <= scaled <= _INT32_MAX else None


@dataclass(frozen=True, slots=True)
class MissionRefusal:
    """Why the vehicle will not take a mission: the MISSION_ACK result and a sentence."""

    result: int  #: a MAV_MISSION_RESULT other than ACCEPTED, e.g. MAV_MISSION_INVALID_PARAM1
    reason: str  #: for the operator (STATUSTEXT) and logs, e.g. "item 2: no key image 99"


def mission_result_name(result: int) -> str:
    """``MAV_MISSION_RESULT`` name for ``result``, e.g. ``"MAV_MISSION_INVALID_PARAM1"``."""
    entry = mavlink.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT({result})"
