"""UdpVehicle: the vehicle sending first (udpout) to a listening ground station, datagrams
parsed on their own, the reply address moved only by verified messages, a thread that
outlives a handler's exception, and closing."""

from __future__ import annotations

import select
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from robot.vehicle.udp_vehicle import REJECT_REPORT_PERIOD_NS, STRANGER_BUDGET, Rejected, UdpVehicle
from shared.clock import NS_PER_S, ManualClock
from shared.errors import IllegalEventError
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.modes import Mode
from shared.udp_link import UdpLink
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


def test_an_unknown_message_does_not_divert_a_listening_vehicle(
        net: Net, rng: np.random.Generator) -> None:
    net.advance(0.5)  # the ground's first HEARTBEAT made it the vehicle's peer
    unknown_id = 0xABCDEF
    assert unknown_id not in mavlink.mavlink_map
    payload = rng.integers(0, 256, 20, dtype=np.uint8).tobytes()
    # Random bytes that happen to frame as a MAVLink 2 packet: no CRC_EXTRA for the id, so
    # pymavlink cannot check the (random) CRC and decodes it as UNKNOWN_11259375.
    garbage = (bytes([0xFD, len(payload), 0, 0, 0, 42, 1]) + unknown_id.to_bytes(3, "little")
               + payload + rng.integers(0, 256, 2, dtype=np.uint8).tobytes())
    with UdpLink.open(f"udpout:127.0.0.1:{net.vehicle.link.local_port}") as stranger:
        stranger.send(garbage)
        sent_ns = net.now_ns
        net.advance(1.0)  # past the vehicle's next HEARTBEAT, which goes out first at 1 s
        assert net.vehicle.endpoint.codec.unknown_packets == 1  # it arrived and decoded
        assert stranger.receive() == []
    assert [t for t, m in net.ground.received
            if m.get_type() == "HEARTBEAT" and t > sent_ns] == [1_000_000_000]
    ack = net.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_HEARTBEAT)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED


#: Wall-clock limit for the live thread's answers, s: generous, for a loaded machine.
PATIENCE_S = 60.0


def test_the_io_thread_outlives_a_handler_exception(live_vehicle: UdpVehicle,
                                                    app: FakeApp) -> None:
    def broken(*args: Any) -> None:
        raise RuntimeError("a bug in the application")

    app.manual_control = broken  # type: ignore[method-assign]
    ground = make_codec(255, 190)
    types: list[str] = []
    with UdpLink.open(f"udpout:127.0.0.1:{live_vehicle.link.local_port}") as link:
        link.send(ground.pack(mavlink.MAVLink_manual_control_message(1, 500, 0, 0, 0, 0)))
        link.send(ground.pack(mavlink.MAVLink_command_long_message(
            1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            int(Mode.HOLD), 0, 0, 0, 0, 0)))
        limit = time.monotonic() + PATIENCE_S
        while not ("COMMAND_ACK" in types and "HEARTBEAT" in types[types.index("COMMAND_ACK"):]):
            assert time.monotonic() < limit, f"the vehicle went quiet after {types}"
            select.select([link], [], [], 0.1)
            types += [m.get_type() for data, _ in link.receive() for m in ground.parse(data)]
    assert app.state.mode is Mode.HOLD
    assert live_vehicle.endpoint.faults.counts() == {"MANUAL_CONTROL: RuntimeError": 1}


def test_close_is_idempotent_and_final(tmp_path: Path, app: FakeApp,
                                       manual_clock: ManualClock) -> None:
    vehicle = make_vehicle(tmp_path, app, manual_clock)
    vehicle.close()
    vehicle.close()
    vehicle.service(0)  # a no-op once closed
    with pytest.raises(IllegalEventError, match="UdpVehicle: event start_thread is not "
                                                "allowed in state CLOSED"):
        vehicle.start_thread()


def flood(port: int, count: int) -> UdpLink:
    """A stranger's socket that sent ``count`` datagrams of garbage to ``port``."""
    stranger = UdpLink.open(f"udpout:127.0.0.1:{port}")
    for i in range(count):
        stranger.send(b"\xfd\x09garbage" + i.to_bytes(4, "little"))
    return stranger


def test_a_flood_of_strangers_is_shed_and_the_station_served_in_the_same_round(
        net: Net, app: FakeApp) -> None:
    net.advance(0.5)  # the ground's HEARTBEAT made it the trusted peer
    taps: list[tuple[str, bytes, int]] = []
    net.vehicle.packet_taps.append(lambda *packet: taps.append(packet))
    count = 300  # more than one old 256-datagram read, less than any kernel's buffer
    with flood(net.vehicle.link.local_port, count):
        net.ground.send(mavlink.MAVLink_manual_control_message(1, 100, 0, 0, 0, 0))
        assert select.select([net.vehicle.link], [], [], 1.0)[0]
        net.vehicle.service(net.now_ns)  # one round
    assert len(app.called("manual_control")) == 1  # after the flood, still in this round
    assert net.vehicle.endpoint.codec.bad_packets == STRANGER_BUDGET
    assert (net.vehicle.shed, net.vehicle.unverified) == (count - STRANGER_BUDGET,
                                                          STRANGER_BUDGET)
    assert [data[7] for way, data, _ in taps if way == "in"] == [69]  # MANUAL_CONTROL only
    net.advance(1.0)  # SYS_STATUS errors_comm counts the corrupt and the shed
    assert net.ground.of_type("SYS_STATUS")[-1].errors_comm == count


def test_rejected_traffic_is_reported_once_per_period(net: Net) -> None:
    reports: list[tuple[Rejected, int]] = []
    net.vehicle.reject_observers.append(lambda rejected, t_ns: reports.append((rejected, t_ns)))
    net.advance(0.5)
    with flood(net.vehicle.link.local_port, 40):
        net.advance(REJECT_REPORT_PERIOD_NS / NS_PER_S)
    net.advance(2 * REJECT_REPORT_PERIOD_NS / NS_PER_S)  # quiet periods: no report
    [(rejected, t_ns)] = reports
    assert (rejected.unverified, rejected.shed) == (STRANGER_BUDGET, 40 - STRANGER_BUDGET)
    assert rejected.period_ns == REJECT_REPORT_PERIOD_NS and t_ns == REJECT_REPORT_PERIOD_NS
