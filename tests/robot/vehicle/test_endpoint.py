"""The vehicle endpoint over real UDP: identity, modes, commands and telemetry streams."""

from __future__ import annotations

from shared.mavlink.dialect import mavlink  # isort: skip  (sets MAVLINK20 before mavutil)

import logging
import math

from pymavlink import mavutil

from robot.mission import MissionState
from robot.vehicle.app_port import ServoTelemetry
from shared.mavlink.commands.vehicle import CAPABILITIES
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import GCS, Net

DO_SET_MODE = mavlink.MAV_CMD_DO_SET_MODE
CUSTOM = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


def arrivals(net: Net, name: str) -> list[tuple[int, object]]:
    """(virtual arrival time ns, message) of every ``name`` the ground received."""
    return [(t, m) for t, m in net.ground.received if m.get_type() == name]


def next_heartbeat(net: Net) -> object:
    """Run until the next HEARTBEAT arrives; return it."""
    count = len(arrivals(net, "HEARTBEAT"))
    net.run(lambda: len(arrivals(net, "HEARTBEAT")) > count)
    return arrivals(net, "HEARTBEAT")[-1][1]


class TestIdentity:
    def test_heartbeat_every_second_from_component_1_as_a_ground_rover(self, net: Net) -> None:
        net.advance(10.0)
        beats = arrivals(net, "HEARTBEAT")
        # The first beat (t = 0) went out before the ground's first datagram told the
        # listening vehicle where the ground is.
        assert [t for t, _ in beats] == [i * 1_000_000_000 for i in range(1, 11)]
        for _, hb in beats:
            assert (hb.get_srcSystem(), hb.get_srcComponent()) == (1, 1)
            assert hb.type == mavlink.MAV_TYPE_GROUND_ROVER
            assert hb.autopilot == mavlink.MAV_AUTOPILOT_GENERIC
            assert hb.base_mode & CUSTOM and hb.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
            assert hb.system_status == mavlink.MAV_STATE_STANDBY
            assert mavutil.mode_string_v10(hb) == "MANUAL"

    def test_autopilot_version_after_the_ack(self, net: Net) -> None:
        ack = net.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert (ack.target_system, ack.target_component) == (GCS.system_id, GCS.component_id)
        types = [m.get_type() for _, m in net.ground.received]
        assert types.index("AUTOPILOT_VERSION") > types.index("COMMAND_ACK")
        (version,) = [m for _, m in net.ground.received if m.get_type() == "AUTOPILOT_VERSION"]
        assert version.capabilities == CAPABILITIES | mavlink.MAV_PROTOCOL_CAPABILITY_FTP
        assert version.uid == 0xC0FFEE


class TestModes:
    def test_do_set_mode_in_the_ardupilot_encoding(self, net: Net, app: FakeApp) -> None:
        assert net.command(DO_SET_MODE, CUSTOM, 4).result == mavlink.MAV_RESULT_ACCEPTED
        assert app.called("set_mode") == [(Mode.HOLD,)]
        hb = next_heartbeat(net)
        assert hb.custom_mode == 4 and mavutil.mode_string_v10(hb) == "HOLD"

    def test_a_mode_change_beats_at_once(self, net: Net, app: FakeApp) -> None:
        net.advance(1.5)  # beats at 1 s and 2 s
        assert net.command(DO_SET_MODE, CUSTOM, 4).result == mavlink.MAV_RESULT_ACCEPTED
        t_ns, hb = arrivals(net, "HEARTBEAT")[-1]
        assert mavutil.mode_string_v10(hb) == "HOLD" and t_ns < 1_600_000_000
        app.update(armed=False)  # the robot's own change: the next poll beats
        net.advance(0.1)
        t_ns, hb = arrivals(net, "HEARTBEAT")[-1]
        assert t_ns < 1_700_000_000 and not hb.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED

    def test_do_set_mode_in_the_px4_encoding(self, net: Net, app: FakeApp) -> None:
        app.update(mode=Mode.HOLD)
        armed = CUSTOM | mavlink.MAV_MODE_FLAG_SAFETY_ARMED  # what MAVSDK sends
        assert net.command(DO_SET_MODE, armed, 1, math.nan).result == mavlink.MAV_RESULT_ACCEPTED
        assert net.command(DO_SET_MODE, armed, 4, 3).result == mavlink.MAV_RESULT_ACCEPTED
        assert app.called("set_mode") == [(Mode.MANUAL,), (Mode.HOLD,)]

    def test_set_mode_message(self, net: Net, app: FakeApp) -> None:
        net.ground.send(mavlink.MAVLink_set_mode_message(1, CUSTOM, 15))
        net.run(lambda: bool(app.called("set_mode")))
        assert app.called("set_mode") == [(Mode.GUIDED,)]
        assert mavutil.mode_string_v10(next_heartbeat(net)) == "GUIDED"

    def test_refused_or_unknown_modes_are_denied(self, net: Net, app: FakeApp) -> None:
        app.accept = False
        assert net.command(DO_SET_MODE, CUSTOM, 4).result == mavlink.MAV_RESULT_DENIED
        assert net.command(DO_SET_MODE, CUSTOM, 3).result == mavlink.MAV_RESULT_DENIED
        assert app.called("set_mode") == [(Mode.HOLD,)]  # mode 3 named none of ours

    def test_auto_without_a_mission_is_denied(self, net: Net, app: FakeApp) -> None:
        # PX4 Mission (AUTO 4, MISSION 4), as MAVSDK's mission_raw.start_mission sends it.
        assert net.command(DO_SET_MODE, CUSTOM, 4, 4).result == mavlink.MAV_RESULT_DENIED
        assert app.called("start_mission") == []
        (notice,) = net.ground.of_type("STATUSTEXT")
        assert notice.text == "mission: cannot run items 0..-1 of 0"


class TestCommands:
    def test_unknown_commands_are_unsupported(self, net: Net) -> None:
        for command in (mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN,
                        mavlink.MAV_CMD_REQUEST_PROTOCOL_VERSION, mavlink.MAV_CMD_USER_4):
            assert net.command(command, 1).result == mavlink.MAV_RESULT_UNSUPPORTED

    def test_get_home_position_is_answered(self, net: Net, app: FakeApp) -> None:
        home = mavlink.MAV_CMD_GET_HOME_POSITION
        assert net.command(home).result == mavlink.MAV_RESULT_DENIED  # not known yet
        app.update(home_pose=(1.5, 2.0, math.pi / 2))
        assert net.command(home).result == mavlink.MAV_RESULT_ACCEPTED
        (position,) = net.ground.of_type("HOME_POSITION")
        # Odometry frame (x forward, y left) to FRD: y and yaw change sign.
        assert (position.x, position.y, position.z) == (1.5, -2.0, 0.0)
        assert math.isclose(position.q[0], math.sqrt(0.5), rel_tol=1e-6)
        assert math.isclose(position.q[3], -math.sqrt(0.5), rel_tol=1e-6)

    def test_arm_disarm_goes_to_the_app(self, net: Net, app: FakeApp) -> None:
        arm = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
        assert net.command(arm, 0).result == mavlink.MAV_RESULT_ACCEPTED
        assert net.command(arm, 1, 21196).result == mavlink.MAV_RESULT_ACCEPTED
        assert app.called("arm") == [(False, False), (True, True)]

    def test_manual_control_reaches_the_app_normalized(self, net: Net, app: FakeApp) -> None:
        net.ground.send(mavlink.MAVLink_manual_control_message(1, 500, -1000, 0x7FFF, 250, 0b101))
        net.ground.send(mavlink.MAVLink_manual_control_message(2, 1000, 0, 0, 0, 0))  # not us
        net.run(lambda: bool(app.called("manual_control")))
        net.advance(0.5)
        [(x, y, z, r, buttons, _)] = app.called("manual_control")
        assert (x, y, r, buttons) == (0.5, -1.0, 0.25, 0b101) and math.isnan(z)

    def test_timesync_is_answered(self, net: Net) -> None:
        net.ground.send(mavlink.MAVLink_timesync_message(0, 12345))
        net.run(lambda: bool(net.ground.of_type("TIMESYNC")))
        (reply,) = net.ground.of_type("TIMESYNC")
        assert reply.ts1 == 12345 and reply.tc1 == net.now_ns


class TestTelemetry:
    def test_default_streams(self, net: Net, app: FakeApp) -> None:
        net.advance(4.0)
        counts = {name: len(net.ground.of_type(name)) for name in (
            "HEARTBEAT", "SYS_STATUS", "BATTERY_STATUS", "MISSION_CURRENT", "ODOMETRY",
            "VISUAL_SERVO_STATUS", "NAV_CONTROLLER_OUTPUT", "HOME_POSITION")}
        # Slots after t = 0 (when the vehicle learned where the ground is) up to t = 4 s.
        assert counts == {"HEARTBEAT": 4, "SYS_STATUS": 4, "BATTERY_STATUS": 4,
                          "MISSION_CURRENT": 4, "ODOMETRY": 16, "VISUAL_SERVO_STATUS": 8,
                          "NAV_CONTROLLER_OUTPUT": 0, "HOME_POSITION": 0}
        battery = net.ground.of_type("BATTERY_STATUS")[-1]
        assert battery.voltages[0] == 12600 and battery.voltages[1] == 0xFFFF
        assert net.ground.of_type("SYS_STATUS")[-1].voltage_battery == 12600
        servo = net.ground.of_type("VISUAL_SERVO_STATUS")[-1]
        assert (servo.state, servo.next_key) == (mavlink.VTR_STATE_IDLE, -1)
        current = net.ground.of_type("MISSION_CURRENT")[-1]
        assert (current.total, current.mission_state) == (0, mavlink.MISSION_STATE_NO_MISSION)

    def test_corrupt_packets_are_counted_in_sys_status(self, net: Net) -> None:
        packet = net.ground.codec.pack(mavlink.MAVLink_command_long_message(
            1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 0, 0, 0, 0, 0, 0, 0))
        flipped = packet[:-3] + bytes([packet[-3] ^ 0xFF]) + packet[-2:]  # a payload byte
        for _ in range(3):
            net.ground.link.send(flipped)
        net.advance(2.0)
        status = net.ground.of_type("SYS_STATUS")[-1]
        assert status.errors_comm == net.vehicle.endpoint.stats().bad_packets == 3
        assert not net.ground.of_type("COMMAND_ACK")  # the corrupt request was dropped

    def test_servo_state_and_cross_track_error(self, net: Net, app: FakeApp) -> None:
        app.update(mission_state=MissionState.FOLLOWING, goal_key=6, odom_pose=(1.0, 0.5, 0.1),
                   servo=ServoTelemetry(current_key=2, next_key=3, matches=87,
                                        err_image_max_px=31.5, err_points_px=12.25, y_m=0.125,
                                        theta_rad=0.1, s_m=-1.6))
        net.advance(1.0)
        nav = net.ground.of_type("NAV_CONTROLLER_OUTPUT")[-1]
        assert nav.xtrack_error == 0.125 and nav.wp_dist == 2
        assert nav.nav_bearing == 354 and nav.target_bearing == 0  # yaw 0.1 rad CCW, theta 0.1
        servo = net.ground.of_type("VISUAL_SERVO_STATUS")[-1]
        assert (servo.current_key, servo.next_key, servo.goal_key, servo.matches) == (2, 3, 6, 87)
        assert (servo.err_image_max, servo.err_points, servo.y) == (31.5, 12.25, 0.125)
        assert servo.state == mavlink.VTR_STATE_FOLLOWING
        assert next_heartbeat(net).system_status == mavlink.MAV_STATE_ACTIVE

    def test_set_message_interval_changes_a_stream_rate(self, net: Net) -> None:
        odometry, interval = mavlink.MAVLINK_MSG_ID_ODOMETRY, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL

        def rate_over(seconds: float) -> int:
            start = net.now_ns
            net.advance(seconds)
            return len([t for t, _ in arrivals(net, "ODOMETRY") if t > start])

        net.advance(1.0)
        assert rate_over(2.0) == 8  # default 4 Hz
        assert net.command(interval, odometry, 100_000).result == mavlink.MAV_RESULT_ACCEPTED
        assert rate_over(2.0) == 20
        assert net.command(interval, odometry, 1_000).result == mavlink.MAV_RESULT_ACCEPTED
        assert rate_over(2.0) == 40  # floored at min_stream_period_ns, 50 ms
        assert net.command(interval, odometry, -1).result == mavlink.MAV_RESULT_ACCEPTED
        assert rate_over(2.0) == 0
        assert net.command(interval, odometry, 0).result == mavlink.MAV_RESULT_ACCEPTED
        assert rate_over(2.0) == 8
        assert net.command(interval, mavlink.MAVLINK_MSG_ID_ATTITUDE, 100_000).result == \
            mavlink.MAV_RESULT_DENIED  # not a stream of ours


class TestNotices:
    def test_application_notices_go_out_as_statustext_at_their_level(
            self, net: Net, app: FakeApp) -> None:
        next_heartbeat(net)  # the listening vehicle knows where the ground is
        app.notices += [(logging.INFO, "path 2 'yard' saved: 14 key images"),
                        (logging.ERROR, "photo 3: not found in the memory")]
        net.run(lambda: len(net.ground.of_type("STATUSTEXT")) >= 2)
        texts = [(m.severity, m.text) for m in net.ground.of_type("STATUSTEXT")]
        assert texts == [(mavlink.MAV_SEVERITY_INFO, "path 2 'yard' saved: 14 key images"),
                         (mavlink.MAV_SEVERITY_ERROR, "photo 3: not found in the memory")]
        assert app.notices == []
