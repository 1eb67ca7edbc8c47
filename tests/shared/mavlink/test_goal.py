"""Goal items: MAV_CMD_WAYPOINT_USER_1 with param1 = key image id, param3 = goal image id."""

from __future__ import annotations

import math

import pytest

from shared.mavlink.address import Address
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.mission.goal import GOAL_COMMAND, MAX_ID, Goal, goal_from_item, goals_from_items
from shared.mavlink.mission.items import MissionItem, MissionRefusal, item_from_message


def test_goal_round_trips_through_a_mission_item_int_on_the_wire() -> None:
    goal = Goal(key_image_id=MAX_ID, goal_image_id=7)
    msg = goal.to_item().to_message(3, Address(1, 1))
    (decoded,) = make_codec(1, 1).parse(make_codec(255, 190).pack(msg))
    assert (decoded.command, decoded.frame, decoded.seq) == (31000, mavlink.MAV_FRAME_MISSION, 3)
    assert goal_from_item(item_from_message(decoded), 3) == goal
    assert GOAL_COMMAND == mavlink.MAV_CMD_WAYPOINT_USER_1


def test_nan_in_optional_params_reads_as_unset_and_any_frame_is_accepted() -> None:
    item = MissionItem(command=31000, frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                       param1=12, param2=math.nan, param3=math.nan, param4=math.nan,
                       x=473978000, y=85457000, z=3.0)
    assert goal_from_item(item, 0) == Goal(12, 0)


@pytest.mark.parametrize(("item", "result", "reason"), [
    (MissionItem(command=16), mavlink.MAV_MISSION_UNSUPPORTED,
     "item 4: command MAV_CMD_NAV_WAYPOINT is not a goal (MAV_CMD_WAYPOINT_USER_1, 31000)"),
    (MissionItem(command=31000, param1=math.nan), mavlink.MAV_MISSION_INVALID_PARAM1,
     "item 4: param1 nan is not a key image id"),
    (MissionItem(command=31000, param1=-1), mavlink.MAV_MISSION_INVALID_PARAM1,
     "item 4: param1 -1.0 is not a key image id"),
    (MissionItem(command=31000, param1=3, param2=42), mavlink.MAV_MISSION_INVALID_PARAM2,
     "item 4: param2 42.0 is reserved (0)"),
    (MissionItem(command=31000, param1=3, param3=0.5), mavlink.MAV_MISSION_INVALID_PARAM3,
     "item 4: param3 0.5 is not a goal image id"),
    (MissionItem(command=31000, param1=3, param4=1), mavlink.MAV_MISSION_INVALID_PARAM4,
     "item 4: param4 1.0 is reserved (0)"),
])
def test_bad_items_get_specific_refusals(item: MissionItem, result: int, reason: str) -> None:
    assert goal_from_item(item, 4) == MissionRefusal(result, reason)


def test_first_bad_item_refuses_the_mission() -> None:
    items = (Goal(1).to_item(), MissionItem(command=31000, param1=2.5), MissionItem(command=16))
    refusal = goals_from_items(items)
    assert isinstance(refusal, MissionRefusal) and refusal.reason.startswith("item 1:")
    assert goals_from_items(items[:1]) == (Goal(1),)


def test_goal_ids_are_range_checked() -> None:
    with pytest.raises(ValueError, match="key_image_id must be in"):
        Goal(MAX_ID + 1)
