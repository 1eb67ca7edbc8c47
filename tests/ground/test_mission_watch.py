"""MissionWatch: reached, stopped short, and stale states that must not count."""

from __future__ import annotations

from ground.mission_watch import MissionWatch
from shared.mavlink.dialect import mavlink
from shared.mavlink.statustext import statustext_messages
from tests.ground.messages import from_system


def current(state: int) -> object:
    return from_system(1, mavlink.MAVLink_mission_current_message(0, 1, state))[0]


def reached(seq: int) -> object:
    return from_system(1, mavlink.MAVLink_mission_item_reached_message(seq))[0]


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


def test_photo_goal_ends_by_notice() -> None:
    watch = MissionWatch(last_seq=None)
    watch.handle_message(reached(0))  # an uploaded mission's item: not this goal
    watch.handle_message(current(mavlink.MISSION_STATE_ACTIVE))
    watch.handle_message(current(mavlink.MISSION_STATE_COMPLETE))
    assert watch.outcome is None
    watch.handle_message(notice("mission arrived: at key image 4"))
    assert watch.outcome is True
    failed = MissionWatch(last_seq=None)
    failed.handle_message(notice("mission failed: no match"))
    assert failed.outcome is False
