"""Stock pymavlink (``mavutil``, as MAVProxy uses it) sees the vehicle, its mode names and
mode changes; the vehicle runs its own I/O thread on the wall clock."""

from __future__ import annotations

from shared.mavlink.dialect import mavlink  # isort: skip  (sets MAVLINK20 before mavutil)

from pymavlink import mavutil

from robot.vehicle.udp_vehicle import UdpVehicle
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp


def test_mavutil_sees_a_rover_with_mode_names(live_vehicle: UdpVehicle, app: FakeApp) -> None:
    conn = mavutil.mavlink_connection(f"udpout:127.0.0.1:{live_vehicle.link.local_port}",
                                      source_system=255, source_component=230)
    try:
        conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        heartbeat = conn.wait_heartbeat(timeout=5)
        assert heartbeat is not None and heartbeat.get_srcComponent() == 1
        assert conn.target_system == 1  # target_component stays 0: any component
        assert conn.flightmode == "MANUAL"
        conn.set_mode("HOLD")  # mode_mapping() for a ground rover; DO_SET_MODE(1, 4)
        ack = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=5)
        assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
        hold = conn.recv_match(type="HEARTBEAT", condition="HEARTBEAT.custom_mode==4",
                               blocking=True, timeout=5)
        assert hold is not None and conn.flightmode == "HOLD"
        assert app.called("set_mode") == [(Mode.HOLD,)]
    finally:
        conn.close()
