"""One-line texts of a vehicle's telemetry, for ``vmnav ground status``, ``watch`` and
``goto --wait`` (pure).

Wire units stop here: mV become V, FRD odometry becomes the robot's FLU frame
(x forward, y left, yaw counter-clockwise; ``robot/vehicle/telemetry.py`` does the
opposite), radians are printed as degrees for people.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ground.fleet import VehicleState, mode_name
from shared.mavlink.dialect import mavlink

_UNKNOWN_MV = 0xFFFF


def _enum_name(enum: str, value: int, prefix: str) -> str:
    """E.g. ``"no mission"`` for (``"MISSION_STATE"``, 1, ``"MISSION_STATE_"``)."""
    entry = mavlink.enums[enum].get(value)
    return entry.name.removeprefix(prefix).lower().replace("_", " ") if entry else str(value)


def battery_v(vehicle: VehicleState) -> float:
    """Battery voltage from SYS_STATUS, V; NaN when unknown or not received."""
    status = vehicle.telemetry.get("SYS_STATUS")
    if status is None or status.voltage_battery == _UNKNOWN_MV:
        return math.nan
    return float(status.voltage_battery) / 1000


def mission_text(msg: Any) -> str:
    """MISSION_CURRENT as ``item 1/3, active``."""
    state = _enum_name("MISSION_STATE", getattr(msg, "mission_state", 0), "MISSION_STATE_")
    return f"item {msg.seq}/{msg.total}, {state}"


def status_line(vehicle: VehicleState, now_ns: int) -> str:
    """One line: system id, mode, state, battery, mission, heartbeat age."""
    state = _enum_name("MAV_STATE", vehicle.system_status, "MAV_STATE_")
    volts = battery_v(vehicle)
    battery = f"{volts:.1f} V" if math.isfinite(volts) else "unknown"
    current = vehicle.telemetry.get("MISSION_CURRENT")
    mission = mission_text(current) if current is not None else "unknown"
    age_s = (now_ns - vehicle.last_heartbeat_ns) / 1e9
    return (f"vehicle {vehicle.system_id}: mode {vehicle.mode_name}, {state}, "
            f"battery {battery}, mission {mission}, heartbeat {age_s:.1f} s ago")


def not_reached_text(outcome: bool | None, waited_s: float, notices: Sequence[str]) -> str:
    """Why a goal was not reached: ``still on the way after 600 s`` (``outcome`` None, the
    wait of ``waited_s`` s over) or ``the run stopped short`` (False), then the vehicle's
    last notice in brackets if it sent any."""
    why = f"still on the way after {waited_s:g} s" if outcome is None else "the run stopped short"
    last = f" (last notice: {notices[-1]})" if notices else ""
    return why + last


def _yaw_flu_deg(q_wxyz: list[float]) -> float:
    """Yaw of a yaw-only FRD attitude quaternion, as a counter-clockwise angle in deg."""
    w, _, _, z = q_wxyz
    return -math.degrees(2 * math.atan2(z, w))


def odometry_flu(msg: Any) -> tuple[float, float, float, float, float]:
    """ODOMETRY in the robot's frame: ``(x_m, y_m, yaw_rad, v_m_s, omega_rad_s)``, x forward,
    y left, yaw and omega counter-clockwise."""
    return (float(msg.x), -float(msg.y), math.radians(_yaw_flu_deg(msg.q)), float(msg.vx),
            -float(msg.yawspeed))


def describe(msg: Any) -> str | None:
    """A line for one telemetry message; None for types not shown (STATUSTEXT included:
    notices are shown joined, from :attr:`VehicleState.notices`)."""
    kind = msg.get_type()
    if kind == "HEARTBEAT":
        state = _enum_name("MAV_STATE", msg.system_status, "MAV_STATE_")
        return f"mode {mode_name(msg.custom_mode)}, {state}"
    if kind == "SYS_STATUS":
        if msg.voltage_battery == _UNKNOWN_MV:
            return "battery unknown"
        return f"battery {msg.voltage_battery / 1000:.2f} V"
    if kind == "MISSION_CURRENT":
        return mission_text(msg)
    if kind == "MISSION_ITEM_REACHED":
        return f"reached item {msg.seq}"
    if kind == "ODOMETRY":
        return (f"x {msg.x:+.2f} m, y {-msg.y:+.2f} m, yaw {_yaw_flu_deg(msg.q):+.1f} deg, "
                f"v {msg.vx:+.2f} m/s, omega {math.degrees(-msg.yawspeed):+.1f} deg/s")
    if kind == "NAV_CONTROLLER_OUTPUT":
        return f"xtrack {msg.xtrack_error:+.3f} m, {msg.wp_dist} m to the next key image"
    if kind == "VISUAL_SERVO_STATUS":
        state = _enum_name("VTR_STATE", msg.state, "VTR_STATE_")
        return (f"{state}: key {msg.current_key} -> {msg.next_key} (goal {msg.goal_key}), "
                f"{msg.matches} matches, errImageMax {msg.err_image_max:.1f} px, "
                f"y {msg.y:+.3f} m, theta {math.degrees(msg.theta):+.1f} deg")
    return None
