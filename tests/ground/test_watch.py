"""WatchLines: the lines of ``vmnav ground watch`` (the loop runs in test_ground_cmd.py)."""

from __future__ import annotations

from ground.fleet import Fleet
from ground.watch import WatchLines
from shared.mavlink.dialect import mavlink
from shared.mavlink.modes import Mode, heartbeat_message
from shared.mavlink.statustext import statustext_messages
from tests.ground.messages import from_system


def test_new_notices_come_once_before_the_line_of_the_message() -> None:
    fleet, watch_lines = Fleet(), WatchLines()
    beat = heartbeat_message(Mode.HOLD, True, mavlink.MAV_STATE_STANDBY)
    notice = statustext_messages(mavlink.MAV_SEVERITY_INFO, "teaching 'a'")
    lines = []
    for msg in from_system(2, beat, *notice, beat):
        vehicle = fleet.handle(msg, None, 0)
        assert vehicle is not None
        lines.append(watch_lines.lines(vehicle, msg, 1.25))
    assert lines == [
        ["    1.25 s  vehicle 2  HEARTBEAT: mode HOLD, standby"],
        ["    1.25 s  vehicle 2  NOTICE: teaching 'a'"],  # STATUSTEXT has no line of its own
        ["    1.25 s  vehicle 2  HEARTBEAT: mode HOLD, standby"],
    ]


def test_notices_are_counted_per_vehicle() -> None:
    fleet, watch_lines = Fleet(), WatchLines()
    notice = statustext_messages(mavlink.MAV_SEVERITY_INFO, "hello")
    for system_id in (1, 2):
        for msg in from_system(system_id, heartbeat_message(Mode.MANUAL, False, 0), *notice):
            vehicle = fleet.handle(msg, None, 0)
        assert vehicle is not None
        assert watch_lines.lines(vehicle, msg, 0.0) == [
            f"    0.00 s  vehicle {system_id}  NOTICE: hello"]
