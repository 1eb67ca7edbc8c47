"""Telemetry messages built from a :class:`~robot.vehicle.app_port.VehicleTelemetry`, and
the schedule that streams them.

Frames: the application's odometry frame is x forward, y left, z up (FLU) with yaw
counter-clockwise; MAVLink wants FRD/NED, so positions go out in
``MAV_FRAME_LOCAL_FRD`` (y and yaw negated) and rates in ``MAV_FRAME_BODY_FRD``
(yaw rate negated). Bearings are compass degrees, clockwise from the odometry x axis.
Wire units (mV, degrees, us) stop here.

The vehicle streams by default (reference/mavlink-vehicle.md sec. 3): every message
of :func:`default_periods_ns` at its config period, changed per message by
SET_MESSAGE_INTERVAL (``shared.mavlink.commands.intervals``). A builder may return None
when it has nothing to say (NAV_CONTROLLER_OUTPUT while no route is followed,
HOME_POSITION before the home is known); its slot passes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from robot.mission import MissionState
from robot.vehicle.app_port import ACTIVE_STATES, VehicleTelemetry
from shared.config import MavlinkConfig
from shared.mavlink.dialect import Message, mavlink

#: (telemetry, time since boot in us) -> the message, or None to skip this slot.
Builder = Callable[[VehicleTelemetry, int], Message | None]

UINT16_MAX = 0xFFFF
INT16_MAX = 0x7FFF

_SENSORS = (mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
            | mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION)

_VTR_STATES = {
    MissionState.IDLE: mavlink.VTR_STATE_IDLE,
    MissionState.LOCALIZING: mavlink.VTR_STATE_LOCALIZING,
    MissionState.FOLLOWING: mavlink.VTR_STATE_FOLLOWING,
    MissionState.LOST: mavlink.VTR_STATE_LOST,
    MissionState.WAITING: mavlink.VTR_STATE_WAITING,
    MissionState.ARRIVED: mavlink.VTR_STATE_ARRIVED,
    MissionState.ABORTED: mavlink.VTR_STATE_ABORTED,
    MissionState.FAILED: mavlink.VTR_STATE_FAILED,
}


def default_periods_ns(config: MavlinkConfig) -> dict[int, int]:
    """Message id -> default stream period, ns (HEARTBEAT has its own fixed period)."""
    return {
        mavlink.MAVLINK_MSG_ID_SYS_STATUS: config.status_period_ns,
        mavlink.MAVLINK_MSG_ID_BATTERY_STATUS: config.status_period_ns,
        mavlink.MAVLINK_MSG_ID_MISSION_CURRENT: config.status_period_ns,
        mavlink.MAVLINK_MSG_ID_ODOMETRY: config.odometry_period_ns,
        mavlink.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: config.odometry_period_ns,
        mavlink.MAVLINK_MSG_ID_VISUAL_SERVO_STATUS: config.servo_status_period_ns,
        mavlink.MAVLINK_MSG_ID_HOME_POSITION: config.home_period_ns,
    }


def system_status(t: VehicleTelemetry, gcs_lost: bool) -> int:
    """HEARTBEAT ``system_status``: CRITICAL in the GCS failsafe or while the base does not
    report, ACTIVE while driving to a goal or teaching, else STANDBY."""
    if gcs_lost or not t.base_reporting:
        return mavlink.MAV_STATE_CRITICAL
    if t.teaching or t.mission_state in ACTIVE_STATES:
        return mavlink.MAV_STATE_ACTIVE
    return mavlink.MAV_STATE_STANDBY


def _millivolts(volts: float) -> int:
    """Voltage in mV for a uint16 field; UINT16_MAX when unknown (common.xml)."""
    if not math.isfinite(volts):
        return UINT16_MAX
    return min(max(round(volts * 1000), 0), UINT16_MAX - 1)


def sys_status_message(t: VehicleTelemetry, time_usec: int, errors_comm: int = 0,
                       handler_faults: int = 0, refused: int = 0) -> Message:
    """SYS_STATUS: motors (enabled when armed, unhealthy while the base does not report),
    battery voltage, vision (unhealthy when LOST),
    and ``errors_comm``: the packets received corrupt so far (common.xml: "dropped packets
    on all links (packets that were corrupted on reception on the MAV)"); common.xml
    leaves ``errors_count1..4`` to the autopilot: ``errors_count1`` carries the
    exceptions of message handlers (``handler_faults``, bugs), ``errors_count2`` the
    messages refused (``refused``: answered with an error or dropped as malformed).
    Each is capped at 65535.

    The GEOFENCE health bit is set although there is no fence: MAVProxy otherwise prints
    a spurious "fence breach" (reference sec. 1.8).
    """
    enabled = _SENSORS if t.armed else _SENSORS & ~mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    health = mavlink.MAV_SYS_STATUS_GEOFENCE
    if t.base_reporting:
        health |= mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
    if math.isfinite(t.battery_v):
        health |= mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
    if t.mission_state is not MissionState.LOST:
        health |= mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION
    return mavlink.MAVLink_sys_status_message(
        _SENSORS, enabled, health, 0, _millivolts(t.battery_v), -1, -1, 0,
        min(errors_comm, UINT16_MAX), min(handler_faults, UINT16_MAX), min(refused, UINT16_MAX),
        0, 0)


def battery_status_message(t: VehicleTelemetry, time_usec: int) -> Message:
    """BATTERY_STATUS: the total voltage in cell 0 (cells are not measured).

    The P3-AT's lead-acid packs have no ``MAV_BATTERY_TYPE``; the type is UNKNOWN.
    """
    voltages = [_millivolts(t.battery_v)] + [UINT16_MAX] * 9
    return mavlink.MAVLink_battery_status_message(
        0, mavlink.MAV_BATTERY_FUNCTION_ALL, mavlink.MAV_BATTERY_TYPE_UNKNOWN, INT16_MAX,
        voltages, -1, -1, -1, -1)


def _quat_wxyz_frd(yaw_flu_rad: float) -> list[float]:
    """Attitude quaternion (w, x, y, z) of a yaw-only pose, FLU yaw -> FRD frame."""
    half = -yaw_flu_rad / 2
    return [math.cos(half), 0.0, 0.0, math.sin(half)]


def _unknown_covariance() -> list[float]:
    return [math.nan] + [0.0] * 20


def odometry_message(t: VehicleTelemetry, time_usec: int) -> Message:
    """ODOMETRY: wheel odometry pose in LOCAL_FRD, velocity and yaw rate in BODY_FRD."""
    x_m, y_m, yaw_rad = t.odom_pose
    v_m_s, omega_rad_s = t.velocity
    return mavlink.MAVLink_odometry_message(
        time_usec, mavlink.MAV_FRAME_LOCAL_FRD, mavlink.MAV_FRAME_BODY_FRD,
        x_m, -y_m, 0.0, _quat_wxyz_frd(yaw_rad), v_m_s, 0.0, 0.0, 0.0, 0.0, -omega_rad_s,
        _unknown_covariance(), _unknown_covariance(),
        estimator_type=mavlink.MAV_ESTIMATOR_TYPE_NAIVE)


def _compass_deg(yaw_flu_rad: float) -> int:
    """Compass bearing, whole degrees 0..359, of a counter-clockwise yaw."""
    return round(math.degrees(-yaw_flu_rad)) % 360


def nav_controller_message(t: VehicleTelemetry, time_usec: int) -> Message | None:
    """NAV_CONTROLLER_OUTPUT while the follower runs; None otherwise.

    ``xtrack_error`` = y (m, + left); ``nav_bearing`` = the robot's heading;
    ``target_bearing`` = the heading of the line through the next key image
    (yaw - theta); ``wp_dist`` = metres left to the next key image (-s, whole m).
    """
    servo = t.servo
    if servo is None:
        return None
    yaw_rad = t.odom_pose[2]
    line_yaw_rad = yaw_rad - servo.theta_rad if math.isfinite(servo.theta_rad) else yaw_rad
    to_go_m = -servo.s_m if math.isfinite(servo.s_m) else 0.0
    return mavlink.MAVLink_nav_controller_output_message(
        0.0, 0.0, _compass_deg(yaw_rad), _compass_deg(line_yaw_rad),
        min(max(round(to_go_m), 0), UINT16_MAX), 0.0, 0.0, servo.y_m)


def _key(key: int | None) -> int:
    return -1 if key is None else key


def visual_servo_message(t: VehicleTelemetry, time_usec: int) -> Message:
    """VISUAL_SERVO_STATUS (project dialect); NaN errors and -1 keys while not following.

    While teaching, ``current_key`` is the last key image taken (the id it gets when the
    path is stored; its thumbnail is ``/teaching/<id>.png`` over FTP), -1 before the first.
    """
    servo = t.servo
    state = mavlink.VTR_STATE_TEACHING if t.teaching else _VTR_STATES[t.mission_state]
    if servo is None:
        current = t.teach_thumbnails[-1][0] if t.teaching and t.teach_thumbnails else -1
        return mavlink.MAVLink_visual_servo_status_message(
            time_usec, current, -1, _key(t.goal_key), 0, math.nan, math.nan, math.nan,
            math.nan, math.nan, state)
    return mavlink.MAVLink_visual_servo_status_message(
        time_usec, _key(servo.current_key), _key(servo.next_key), _key(t.goal_key),
        min(servo.matches, UINT16_MAX), servo.err_image_max_px, servo.err_points_px,
        servo.y_m, servo.theta_rad, servo.s_m, state)


def home_position_message(t: VehicleTelemetry, time_usec: int) -> Message | None:
    """HOME_POSITION in LOCAL_FRD (no GPS: latitude, longitude, altitude 0); None if unknown."""
    if t.home_pose is None:
        return None
    x_m, y_m, yaw_rad = t.home_pose
    return mavlink.MAVLink_home_position_message(
        0, 0, 0, x_m, -y_m, 0.0, _quat_wxyz_frd(yaw_rad), 0.0, 0.0, 0.0, time_usec)


#: The builders of the streams that depend on the telemetry alone (SYS_STATUS also counts
#: the link's corrupt packets: the endpoint builds it).
TELEMETRY_BUILDERS: dict[int, Builder] = {
    mavlink.MAVLINK_MSG_ID_BATTERY_STATUS: battery_status_message,
    mavlink.MAVLINK_MSG_ID_ODOMETRY: odometry_message,
    mavlink.MAVLINK_MSG_ID_NAV_CONTROLLER_OUTPUT: nav_controller_message,
    mavlink.MAVLINK_MSG_ID_VISUAL_SERVO_STATUS: visual_servo_message,
    mavlink.MAVLINK_MSG_ID_HOME_POSITION: home_position_message,
}


class TelemetryStreams:
    """When each streamed message is due.

    A message goes out first on the poll after it is enabled (or its period changes),
    then every period; a late poll re-anchors the schedule instead of bursting.

    Args:
        builders: message id -> builder.
        period_ns: message id -> its period now, ns; None when the stream is off.
    """

    def __init__(self, builders: Mapping[int, Builder],
                 period_ns: Callable[[int], int | None]) -> None:
        self._builders = dict(builders)
        self._period_ns = period_ns
        self._due: dict[int, tuple[int, int]] = {}  # id -> (period used, next due ns)

    def due(self, t: VehicleTelemetry, now_ns: int, time_usec: int) -> list[Message]:
        """The messages due at ``now_ns``, built from ``t``."""
        out: list[Message] = []
        for msg_id, build in self._builders.items():
            period = self._period_ns(msg_id)
            if period is None:
                self._due.pop(msg_id, None)
                continue
            used, due_ns = self._due.get(msg_id, (period, now_ns))
            if used != period:
                due_ns = now_ns
            if now_ns < due_ns:
                continue
            msg = build(t, time_usec)
            if msg is not None:
                out.append(msg)
            due_ns += period
            self._due[msg_id] = (period, due_ns if due_ns > now_ns else now_ns + period)
        return out

    def get_timer(self) -> int | None:
        """The next due time, ns; 0 (at once) while a stream waits for its first slot."""
        deadlines = []
        for msg_id in self._builders:
            period = self._period_ns(msg_id)
            if period is None:
                continue
            used, due_ns = self._due.get(msg_id, (None, 0))
            deadlines.append(due_ns if used == period else 0)
        return min(deadlines) if deadlines else None
