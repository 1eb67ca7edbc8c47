"""MissionWatch: reached, stopped short, and stale states that must not count; STATUSTEXT
is for people and never decides."""

from __future__ import annotations

import math

from ground.mission_watch import MissionWatch
from shared.mavlink.dialect import mavlink
from shared.mavlink.statustext import statustext_messages
from tests.ground.messages import from_system


def current(state: int) -> object:
    return from_system(1, mavlink.MAVLink_mission_current_message(0, 1, state))[0]


def reached(seq: int) -> object:
    return from_system(1, mavlink.MAVLink_mission_item_reached_message(seq))[0]


def servo(state: int) -> object:
    return from_system(1, mavlink.MAVLink_visual_servo_status_message(
        0, -1, -1, 4, 0, math.nan, math.nan, math.nan, math.nan, math.nan, state))[0]


def notice(text: str) -> object:
    return from_system(1, *statustext_messages(mavlink.MAV_SEVERITY_INFO, text))[0]


def test_last_item_reached() -> None:
    watch = MissionWatch(last_seq=1)
    watch.handle_message(reached(0))
    assert watch.outcome is None
    watch.handle_message(reached(1))
    assert watch.outcome is True


def test_complete_counts_only_after_active() -> None:
    watch = MissionWatch(last_seq=0)
    watch.handle_message(current(mavlink.MISSION_STATE_COMPLETE))  # left from the last run
    assert watch.outcome is None
    watch.handle_message(current(mavlink.MISSION_STATE_ACTIVE))
    watch.handle_message(current(mavlink.MISSION_STATE_COMPLETE))
    assert watch.outcome is True


def test_paused_after_active_is_not_reached() -> None:
    watch = MissionWatch(last_seq=0)
    watch.handle_message(current(mavlink.MISSION_STATE_PAUSED))
    assert watch.outcome is None
    watch.handle_message(current(mavlink.MISSION_STATE_ACTIVE))
    watch.handle_message(current(mavlink.MISSION_STATE_PAUSED))
    watch.handle_message(reached(0))  # the outcome is final
    assert watch.outcome is False


def test_photo_goal_ends_by_visual_servo_status() -> None:
    watch = MissionWatch(last_seq=None)
    watch.handle_message(reached(0))  # an uploaded mission's item: not this goal
    watch.handle_message(current(mavlink.MISSION_STATE_ACTIVE))
    watch.handle_message(current(mavlink.MISSION_STATE_COMPLETE))
    assert watch.outcome is None
    watch.handle_message(servo(mavlink.VTR_STATE_LOCALIZING))
    watch.handle_message(servo(mavlink.VTR_STATE_FOLLOWING))
    assert watch.outcome is None
    watch.handle_message(servo(mavlink.VTR_STATE_ARRIVED))
    assert watch.outcome is True
    for final in (mavlink.VTR_STATE_ABORTED, mavlink.VTR_STATE_FAILED):
        stopped = MissionWatch(last_seq=None)
        stopped.handle_message(servo(mavlink.VTR_STATE_LOST))
        stopped.handle_message(servo(final))
        assert stopped.outcome is False


def test_the_last_runs_final_state_does_not_count() -> None:
    watch = MissionWatch(last_seq=0)
    watch.handle_message(servo(mavlink.VTR_STATE_FAILED))  # streamed since the last run
    watch.handle_message(servo(mavlink.VTR_STATE_ARRIVED))
    assert watch.outcome is None
    watch.handle_message(servo(mavlink.VTR_STATE_LOCALIZING))
    watch.handle_message(servo(mavlink.VTR_STATE_ABORTED))
    watch.handle_message(reached(0))  # the outcome is final
    assert watch.outcome is False


def test_statustext_does_not_decide() -> None:
    watch = MissionWatch(last_seq=None)
    watch.handle_message(servo(mavlink.VTR_STATE_FOLLOWING))
    watch.handle_message(notice("mission arrived: at key image 4"))
    watch.handle_message(notice("mission failed: no match"))
    assert watch.outcome is None
