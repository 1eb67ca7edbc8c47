"""What the page shows of each vehicle, as JSON-ready dicts (pure).

Units are SI and frames the robot's (``ground.telemetry_text`` converts from the wire);
an unknown number is ``None`` (JSON ``null``): JSON has no NaN, and the browser's
``JSON.parse`` refuses Python's ``NaN``.

Failsafes (:func:`failsafes`) are read from the vehicle's own structured messages, never
from STATUSTEXT:

* ``no heartbeat``: none for :data:`LINK_LOST_S` (this station's view of the link);
* ``critical``: HEARTBEAT ``system_status`` CRITICAL (the robot's ground-station failsafe,
  or its base not reporting: ``robot/vehicle/telemetry.py``);
* ``base not reporting``, ``vision lost``, ``battery unknown``: a sensor SYS_STATUS
  reports present but not healthy.
"""

from __future__ import annotations

import math
from typing import Any

from ground.fleet import VehicleState
from ground.telemetry_text import battery_v, odometry_flu
from shared.mavlink.dialect import mavlink

#: No HEARTBEAT for this long shows the ``no heartbeat`` failsafe, s (the robot beats at 1 Hz).
LINK_LOST_S = 3.0

_HEALTH = (
    (mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS, "base not reporting"),
    (mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION, "vision lost"),
    (mavlink.MAV_SYS_STATUS_SENSOR_BATTERY, "battery unknown"),
)


def finite(value: float) -> float | None:
    """``value``, or None when it is NaN or infinite."""
    return float(value) if math.isfinite(value) else None


def enum_text(enum: str, value: int, prefix: str) -> str:
    """E.g. ``"following"`` for (``"VTR_STATE"``, 2, ``"VTR_STATE_"``); the number when unknown."""
    entry = mavlink.enums[enum].get(value)
    return entry.name.removeprefix(prefix).lower().replace("_", " ") if entry else str(value)


def failsafes(vehicle: VehicleState, now_ns: int) -> list[str]:
    """The vehicle's failsafes in force (module docstring), most serious first."""
    out = []
    age_s = (now_ns - vehicle.last_heartbeat_ns) / 1e9
    if age_s > LINK_LOST_S:
        out.append(f"no heartbeat for {age_s:.0f} s")
    if vehicle.system_status == mavlink.MAV_STATE_CRITICAL:
        out.append("critical")
    status = vehicle.telemetry.get("SYS_STATUS")
    if status is not None:
        present = status.onboard_control_sensors_present
        enabled = status.onboard_control_sensors_enabled
        healthy = status.onboard_control_sensors_health
        out += [text for bit, text in _HEALTH if present & enabled & bit and not healthy & bit]
    return out


def vehicle_name(vehicle: VehicleState) -> str:
    """A name for people: the HEARTBEAT's vehicle type and the system id (MAVLink carries
    no vehicle name), e.g. ``"ground rover 1"``."""
    beat = vehicle.telemetry.get("HEARTBEAT")
    kind = enum_text("MAV_TYPE", beat.type, "MAV_TYPE_") if beat is not None else "vehicle"
    return f"{kind} {vehicle.system_id}"


def vehicle_json(vehicle: VehicleState, now_ns: int,
                 received_share: float | None) -> dict[str, Any]:
    """One row of the fleet view and the head of the vehicle view.

    Args:
        vehicle: as the station knows it.
        now_ns: the station clock now, ns.
        received_share: link quality, 0..1 (``ground.web.link_quality``); None if unknown.
    """
    current = vehicle.telemetry.get("MISSION_CURRENT")
    servo = vehicle.telemetry.get("VISUAL_SERVO_STATUS")
    mission = None
    if current is not None:
        mission = {"seq": current.seq, "total": current.total,
                   "state": enum_text("MISSION_STATE", getattr(current, "mission_state", 0),
                                      "MISSION_STATE_")}
    return {
        "system_id": vehicle.system_id,
        "name": vehicle_name(vehicle),
        "mode": vehicle.mode_name,
        "armed": vehicle.armed,
        "status": enum_text("MAV_STATE", vehicle.system_status, "MAV_STATE_"),
        "battery_v": finite(battery_v(vehicle)),
        "heartbeat_age_s": round((now_ns - vehicle.last_heartbeat_ns) / 1e9, 1),
        "link_received": None if received_share is None else round(received_share, 3),
        "mission": mission,
        "servo_state": (enum_text("VTR_STATE", servo.state, "VTR_STATE_")
                        if servo is not None else None),
        "failsafes": failsafes(vehicle, now_ns),
        "notices": len(vehicle.notices),
    }


def sample_json(msg: Any, t_s: float) -> dict[str, Any] | None:
    """A point of the vehicle view's plots and trail, from one message; None for other types.

    Args:
        msg: a message from the vehicle.
        t_s: when it arrived, s since the server started.
    """
    kind = msg.get_type()
    if kind == "ODOMETRY":
        x_m, y_m, yaw_rad, v_m_s, omega_rad_s = odometry_flu(msg)
        return {"kind": "odom", "t": round(t_s, 3), "x": finite(x_m), "y": finite(y_m),
                "yaw": finite(yaw_rad), "v": finite(v_m_s), "omega": finite(omega_rad_s)}
    if kind == "VISUAL_SERVO_STATUS":
        return {"kind": "servo", "t": round(t_s, 3),
                "state": enum_text("VTR_STATE", msg.state, "VTR_STATE_"),
                "current": msg.current_key, "next": msg.next_key, "goal": msg.goal_key,
                "matches": msg.matches, "err_max": finite(msg.err_image_max),
                "err_mean": finite(msg.err_points), "y": finite(msg.y),
                "theta": finite(msg.theta), "s": finite(msg.s)}
    return None
