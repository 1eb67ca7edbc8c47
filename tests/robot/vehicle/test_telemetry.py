"""Telemetry messages from a snapshot (frames, units, unknowns) and the stream schedule."""

from __future__ import annotations

import math

from robot.mission import MissionState
from robot.vehicle.app_port import ServoTelemetry, VehicleTelemetry
from robot.vehicle.telemetry import (
    Builder,
    TelemetryStreams,
    battery_status_message,
    nav_controller_message,
    odometry_message,
    sys_status_message,
    system_status,
    visual_servo_message,
)
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.modes import Mode

MS = 1_000_000


def through_the_wire(msg: object) -> object:
    """``msg`` packed and parsed again, as the ground receives it."""
    (received,) = make_codec(255, 190).parse(make_codec(1, 1).pack(msg))
    return received


class TestBuilders:
    def test_odometry_is_frd(self) -> None:
        t = VehicleTelemetry(Mode.AUTO, odom_pose=(2.0, 1.0, math.pi / 2), velocity=(0.2, 0.1))
        odom = through_the_wire(odometry_message(t, 1234))
        assert (odom.frame_id, odom.child_frame_id) == (mavlink.MAV_FRAME_LOCAL_FRD,
                                                        mavlink.MAV_FRAME_BODY_FRD)
        assert (odom.x, odom.y, odom.z, odom.time_usec) == (2.0, -1.0, 0.0, 1234)
        # Facing +y (left) in FLU is facing -y (west of x) in FRD: yaw -90 deg about down.
        w, x, y, z = odom.q
        assert math.isclose(w, math.sqrt(0.5), rel_tol=1e-6) and x == y == 0
        assert math.isclose(z, -math.sqrt(0.5), rel_tol=1e-6)
        assert math.isclose(odom.vx, 0.2, rel_tol=1e-6)
        assert math.isclose(odom.yawspeed, -0.1, rel_tol=1e-6)
        assert math.isnan(odom.pose_covariance[0]) and math.isnan(odom.velocity_covariance[0])

    def test_unknown_battery_voltage(self) -> None:
        t = VehicleTelemetry(Mode.MANUAL)
        assert battery_status_message(t, 0).voltages == [0xFFFF] * 10
        status = sys_status_message(t, 0)
        assert status.voltage_battery == 0xFFFF
        assert not status.onboard_control_sensors_health & mavlink.MAV_SYS_STATUS_SENSOR_BATTERY

    def test_sys_status_health_follows_the_robot(self) -> None:
        lost = sys_status_message(VehicleTelemetry(Mode.AUTO, MissionState.LOST,
                                                   armed=True, battery_v=12.0), 0)
        vision = mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION
        motors = mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS
        assert not lost.onboard_control_sensors_health & vision
        assert lost.onboard_control_sensors_enabled & motors
        assert lost.onboard_control_sensors_health & mavlink.MAV_SYS_STATUS_GEOFENCE
        assert lost.onboard_control_sensors_health & motors
        disarmed = sys_status_message(VehicleTelemetry(Mode.MANUAL), 0)
        assert not disarmed.onboard_control_sensors_enabled & motors
        quiet = sys_status_message(VehicleTelemetry(Mode.AUTO, armed=True,
                                                    base_reporting=False), 0)
        assert not quiet.onboard_control_sensors_health & motors

    def test_no_nav_controller_output_without_the_follower(self) -> None:
        assert nav_controller_message(VehicleTelemetry(Mode.AUTO), 0) is None
        unknown = nav_controller_message(VehicleTelemetry(Mode.AUTO, servo=ServoTelemetry()), 0)
        assert unknown is not None and unknown.wp_dist == 0 and math.isnan(unknown.xtrack_error)

    def test_servo_status_while_teaching_and_idle(self) -> None:
        teaching = visual_servo_message(VehicleTelemetry(Mode.MANUAL, teaching=True), 5)
        assert teaching.state == mavlink.VTR_STATE_TEACHING
        assert (teaching.current_key, teaching.next_key, teaching.goal_key) == (-1, -1, -1)
        assert math.isnan(teaching.y)
        taken = visual_servo_message(VehicleTelemetry(
            Mode.MANUAL, teaching=True, teach_thumbnails=((7, b"a"), (8, b"b"))), 5)
        assert (taken.current_key, taken.next_key) == (8, -1)  # the last key image taken

    def test_system_status(self) -> None:
        idle, driving = VehicleTelemetry(Mode.HOLD), VehicleTelemetry(
            Mode.AUTO, MissionState.FOLLOWING)
        assert system_status(idle, gcs_lost=False) == mavlink.MAV_STATE_STANDBY
        assert system_status(driving, gcs_lost=False) == mavlink.MAV_STATE_ACTIVE
        assert system_status(driving, gcs_lost=True) == mavlink.MAV_STATE_CRITICAL
        quiet_base = VehicleTelemetry(Mode.AUTO, MissionState.FOLLOWING, base_reporting=False)
        assert system_status(quiet_base, gcs_lost=False) == mavlink.MAV_STATE_CRITICAL


class TestStreams:
    def make(self, periods: dict[int, int | None]) -> tuple[TelemetryStreams, list[int]]:
        sent: list[int] = []

        def builder(msg_id: int) -> Builder:
            def build(t: VehicleTelemetry, time_usec: int) -> Message:
                sent.append(msg_id)
                return mavlink.MAVLink_heartbeat_message(0, 0, 0, msg_id, 0, 3)
            return build

        streams = TelemetryStreams({1: builder(1), 2: builder(2)}, periods.get)
        return streams, sent

    def test_first_at_once_then_every_period(self) -> None:
        streams, sent = self.make({1: 100 * MS, 2: 250 * MS})
        t = VehicleTelemetry(Mode.MANUAL)
        assert streams.get_timer() == 0
        for now in range(0, 501 * MS, 50 * MS):
            streams.due(t, now, 0)
        assert sent.count(1) == 6 and sent.count(2) == 3
        assert streams.get_timer() == 600 * MS

    def test_a_late_poll_reanchors_instead_of_bursting(self) -> None:
        streams, sent = self.make({1: 100 * MS, 2: None})
        t = VehicleTelemetry(Mode.MANUAL)
        streams.due(t, 0, 0)
        assert len(streams.due(t, 1000 * MS, 0)) == 1
        assert streams.get_timer() == 1100 * MS and sent == [1, 1]

    def test_a_period_change_restarts_the_stream(self) -> None:
        periods: dict[int, int | None] = {1: 1000 * MS}
        streams, sent = self.make(periods)
        t = VehicleTelemetry(Mode.MANUAL)
        streams.due(t, 0, 0)
        periods[1] = 200 * MS
        assert streams.get_timer() == 0
        streams.due(t, 10 * MS, 0)
        assert streams.get_timer() == 210 * MS and sent == [1, 1]
        periods[1] = None
        assert streams.due(t, 300 * MS, 0) == [] and streams.get_timer() is None
