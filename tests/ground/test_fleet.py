"""Fleet: vehicles from their heartbeats, telemetry by type, STATUSTEXT chunks joined."""

from __future__ import annotations

from ground.fleet import Fleet, mode_name
from shared.mavlink.dialect import mavlink
from shared.mavlink.modes import Mode, heartbeat_message
from shared.mavlink.statustext import statustext_messages
from tests.ground.messages import from_system


def test_vehicles_by_system_id() -> None:
    fleet = Fleet()
    gcs = mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                            0, 0, 0, 3)
    status = mavlink.MAVLink_sys_status_message(0, 0, 0, 0, 12600, -1, -1, 0, 0, 0, 0, 0, 0)
    for msg in from_system(3, status, gcs):  # telemetry before the first beat; not a vehicle
        assert fleet.handle(msg, ("127.0.0.1", 5), 0) is None
    beat = heartbeat_message(Mode.HOLD, True, mavlink.MAV_STATE_STANDBY)
    for msg in from_system(3, beat, status):
        fleet.handle(msg, ("127.0.0.1", 7), 10)
    vehicle = fleet.vehicles[3]
    assert (vehicle.mode, vehicle.mode_name, vehicle.last_heartbeat_ns) == (Mode.HOLD, "HOLD", 10)
    assert vehicle.peer == ("127.0.0.1", 7)
    assert vehicle.telemetry["SYS_STATUS"].voltage_battery == 12600
    assert list(fleet.vehicles) == [3]
    assert mode_name(7) == "mode 7"


def test_statustext_chunks_are_joined() -> None:
    fleet = Fleet()
    long_text = "x" * 50 + "y" * 50  # two full chunks and an empty one
    messages = [heartbeat_message(Mode.MANUAL, False, 0),
                *statustext_messages(mavlink.MAV_SEVERITY_INFO, "short"),
                *statustext_messages(mavlink.MAV_SEVERITY_INFO, long_text, chunk_id=9),
                *statustext_messages(mavlink.MAV_SEVERITY_INFO, "z" * 60, chunk_id=10)]
    for msg in from_system(1, *messages):
        fleet.handle(msg, None, 0)
    assert fleet.vehicles[1].notices == ["short", long_text, "z" * 60]
