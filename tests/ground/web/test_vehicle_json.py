"""vehicle_json and sample_json: what the page shows, from real messages of the dialect."""

from __future__ import annotations

import json
import math

from ground.fleet import Fleet
from ground.web.vehicle_json import failsafes, sample_json, vehicle_json
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.modes import Mode

NS = 1_000_000_000
_SENSORS = (mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
            | mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION)


def received(msg):
    """``msg`` as the station receives it: packed by vehicle 1 and parsed."""
    vehicle, station = make_codec(1, 1), make_codec(255, 190)
    (parsed,) = station.parse(vehicle.pack(msg))
    return parsed


def heard(fleet: Fleet, *messages) -> None:
    for msg in messages:
        fleet.handle(received(msg), ("127.0.0.1", 1), 0)


def heartbeat(state: int = mavlink.MAV_STATE_STANDBY):
    return mavlink.MAVLink_heartbeat_message(
        mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_GENERIC,
        mavlink.MAV_MODE_FLAG_SAFETY_ARMED, int(Mode.HOLD), state, 3)


def sys_status(health: int, millivolts: int = 12600):
    return mavlink.MAVLink_sys_status_message(_SENSORS, _SENSORS, health, 0, millivolts, -1, -1,
                                              0, 0, 0, 0, 0, 0)


def test_a_healthy_vehicle() -> None:
    fleet = Fleet()
    heard(fleet, heartbeat(), sys_status(_SENSORS))
    shown = vehicle_json(fleet.vehicles[1], NS // 2, 0.98)
    assert shown == {
        "system_id": 1, "name": "ground rover 1", "mode": "HOLD", "armed": True,
        "status": "standby", "battery_v": 12.6, "heartbeat_age_s": 0.5, "link_received": 0.98,
        "mission": None, "servo_state": None, "failsafes": [], "notices": 0}
    json.dumps(shown, allow_nan=False)


def test_failsafes_from_the_vehicles_messages_and_the_heartbeats_age() -> None:
    fleet = Fleet()
    heard(fleet, heartbeat(mavlink.MAV_STATE_CRITICAL),
          sys_status(mavlink.MAV_SYS_STATUS_SENSOR_BATTERY, millivolts=0xFFFF))
    vehicle = fleet.vehicles[1]
    assert failsafes(vehicle, 5 * NS) == [
        "no heartbeat for 5 s", "critical", "base not reporting", "vision lost"]
    assert vehicle_json(vehicle, 0, None)["battery_v"] is None


def test_samples_in_the_robots_frame_with_unknowns_as_null() -> None:
    odometry = received(mavlink.MAVLink_odometry_message(
        0, mavlink.MAV_FRAME_LOCAL_FRD, mavlink.MAV_FRAME_BODY_FRD, 1.5, 0.25, 0.0,
        [math.cos(-0.25), 0.0, 0.0, math.sin(-0.25)], 0.2, 0.0, 0.0, 0.0, 0.0, -0.1,
        [math.nan] + [0.0] * 20, [math.nan] + [0.0] * 20))
    sample = sample_json(odometry, 1.25)
    assert sample["kind"] == "odom" and sample["t"] == 1.25
    assert [round(sample[k], 6) for k in ("x", "y", "yaw", "v", "omega")] == \
        [1.5, -0.25, 0.5, 0.2, 0.1]
    servo = sample_json(received(mavlink.MAVLink_visual_servo_status_message(
        0, -1, -1, 4, 0, math.nan, math.nan, math.nan, math.nan, math.nan,
        mavlink.VTR_STATE_LOCALIZING)), 2.0)
    assert servo == {"kind": "servo", "t": 2.0, "state": "localizing", "current": -1,
                     "next": -1, "goal": 4, "matches": 0, "err_max": None, "err_mean": None,
                     "y": None, "theta": None, "s": None}
    assert sample_json(received(heartbeat()), 0.0) is None
