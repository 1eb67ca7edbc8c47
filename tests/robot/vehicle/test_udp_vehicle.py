"""UdpVehicle: the vehicle sending first (udpout) to a listening ground station, and closing."""

from __future__ import annotations

from pathlib import Path

import pytest

from shared.clock import ManualClock
from shared.errors import IllegalEventError
from shared.mavlink.dialect import mavlink
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, make_vehicle


def test_udpout_vehicle_reaches_a_listening_ground(tmp_path: Path, app: FakeApp,
                                                   manual_clock: ManualClock) -> None:
    ground = Ground("udpin:127.0.0.1:0", heartbeat=False)
    vehicle = make_vehicle(tmp_path, app, manual_clock,
                           url=f"udpout:127.0.0.1:{ground.link.local_port}")
    taps: list[tuple[str, bytes, int]] = []
    vehicle.packet_taps.append(lambda *packet: taps.append(packet))
    net = Net(manual_clock, vehicle, ground)
    try:
        net.advance(2.0)
        assert [t for t, m in ground.received if m.get_type() == "HEARTBEAT"] == [
            0, 1_000_000_000, 2_000_000_000]  # the first beat too: no need to hear first
        ground.send(*ground.params.get("CTL_SPEED", net.now_ns))  # and it answers
        assert net.until_event(ground.params).name == "CTL_SPEED"
        outs = [(t, data[7]) for d, data, t in taps if d == "out"]  # (time, msg id low byte)
        assert outs[0] == (0, 0) and all(data[0] == 0xFD for _, data, _ in taps)
        (request,) = [data for d, data, _ in taps if d == "in"]
        assert request[7] == 20  # PARAM_REQUEST_READ, the only datagram the ground sent
    finally:
        net.close()


def test_garbage_in_one_datagram_does_not_hold_up_the_next(net: Net) -> None:
    net.ground.link.send(b"\xfd\xff\x00")  # the start of a 255-byte packet, cut short
    ack = net.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_HEARTBEAT)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED and net.now_ns < 1_000_000_000
    assert net.vehicle.endpoint.stats().bad_packets == 1


def test_close_is_idempotent_and_final(tmp_path: Path, app: FakeApp,
                                       manual_clock: ManualClock) -> None:
    vehicle = make_vehicle(tmp_path, app, manual_clock)
    vehicle.close()
    vehicle.close()
    vehicle.service(0)  # a no-op once closed
    with pytest.raises(IllegalEventError, match="UdpVehicle: event start_thread is not "
                                                "allowed in state CLOSED"):
        vehicle.start_thread()
