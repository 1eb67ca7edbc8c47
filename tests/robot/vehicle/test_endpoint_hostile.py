"""Hostile and broken input at the vehicle over real UDP (issue 15): every message is checked
before use and refused with the protocol's error, and no handler exception ends the link."""

from __future__ import annotations

import logging
import math
import random
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import VehicleFiles
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import VEHICLE, Net
from tests.robot.vehicle.test_endpoint_mission import GOALS, download, items_of, upload
from tools.bench.hostile_messages import HANDLED_MESSAGES, random_message

CUSTOM = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
SYS_STATUS = mavlink.MAVLINK_MSG_ID_SYS_STATUS


def after(net: Net, start: int, name: str) -> list[Any]:
    """Messages of type ``name`` the ground received since ``start`` messages."""
    return [m for _, m in net.ground.received[start:] if m.get_type() == name]


def send_item(net: Net, frame: int, x: float, y: float) -> Any:
    """MISSION_COUNT(1) then a deprecated MISSION_ITEM of goal 1 at (x, y) in ``frame``;
    run until the vehicle's MISSION_ACK; return it."""
    start = len(net.ground.received)
    net.ground.send(mavlink.MAVLink_mission_count_message(1, 1, 1, 0),
                    mavlink.MAVLink_mission_item_message(1, 1, 0, frame, 31000, 0, 1, 1, 0, 0,
                                                         0, x, y, 0.0))
    net.run(lambda: bool(after(net, start, "MISSION_ACK")))
    return after(net, start, "MISSION_ACK")[0]


def hold_is_obeyed(net: Net, app: FakeApp) -> bool:
    """DO_SET_MODE HOLD is acknowledged, applied and shown in the next HEARTBEAT."""
    ack = net.command(mavlink.MAV_CMD_DO_SET_MODE, CUSTOM, int(Mode.HOLD))
    start = len(net.ground.received)
    net.run(lambda: bool(after(net, start, "HEARTBEAT")))
    return (ack.result == mavlink.MAV_RESULT_ACCEPTED and app.state.mode is Mode.HOLD
            and after(net, start, "HEARTBEAT")[0].custom_mode == Mode.HOLD)


def sys_status(net: Net) -> Any:
    """A SYS_STATUS asked for now (REQUEST_MESSAGE)."""
    start = len(net.ground.received)
    net.command(mavlink.MAV_CMD_REQUEST_MESSAGE, SYS_STATUS)
    return after(net, start, "SYS_STATUS")[0]


@pytest.mark.parametrize(("x", "y", "result"), [
    (math.nan, 0.0, mavlink.MAV_MISSION_INVALID_PARAM5_X),
    (math.inf, 0.0, mavlink.MAV_MISSION_INVALID_PARAM5_X),
    (0.0, -math.inf, mavlink.MAV_MISSION_INVALID_PARAM6_Y),
])
def test_legacy_item_not_finite_gets_a_mission_ack_error_and_hold_still_works(
        net: Net, app: FakeApp, x: float, y: float, result: int) -> None:
    app.update(mode=Mode.GUIDED)
    assert send_item(net, mavlink.MAV_FRAME_MISSION, x, y).type == result
    assert hold_is_obeyed(net, app)
    assert net.vehicle.endpoint.stats().handler_faults == {}


def test_legacy_item_at_1000_deg_is_refused_and_the_mission_still_downloads(
        net: Net, app: FakeApp) -> None:
    upload(net, items_of(GOALS))
    assert send_item(net, mavlink.MAV_FRAME_GLOBAL, 1000.0, 8.5).type == \
        mavlink.MAV_MISSION_INVALID_PARAM5_X
    assert download(net) == items_of(GOALS)


def test_upload_while_the_mission_runs_is_denied_before_any_item_is_requested(
        net: Net, app: FakeApp) -> None:
    upload(net, items_of(GOALS))
    net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)
    start = len(net.ground.received)
    net.ground.send(mavlink.MAVLink_mission_count_message(1, 1, 1, 0))
    net.run(lambda: bool(after(net, start, "MISSION_ACK")))
    assert after(net, start, "MISSION_ACK")[0].type == mavlink.MAV_MISSION_DENIED
    assert after(net, start, "MISSION_REQUEST_INT") == []
    assert app.called("validate_goals") == [(GOALS,)]  # only the first upload's


def test_handler_exception_is_counted_logged_once_and_the_link_goes_on(
        net: Net, app: FakeApp, caplog: pytest.LogCaptureFixture) -> None:
    def broken(*args: Any) -> None:
        raise RuntimeError("a bug in the application")

    app.manual_control = broken  # type: ignore[method-assign]
    stick = mavlink.MAVLink_manual_control_message(1, 500, 0, 0, 0, 0)
    with caplog.at_level(logging.ERROR, logger="robot.vehicle.endpoint"):
        net.ground.send(stick, stick)
        assert hold_is_obeyed(net, app)
    assert net.vehicle.endpoint.stats().handler_faults == {"MANUAL_CONTROL: RuntimeError": 2}
    assert sys_status(net).errors_count1 == 2
    (record,) = caplog.records
    assert "MANUAL_CONTROL: RuntimeError: a bug in the application" in record.getMessage()
    assert record.exc_info is not None


def test_exception_of_a_tap_is_counted_and_the_next_round_runs(net: Net, app: FakeApp) -> None:
    calls: list[str] = []

    def tap(direction: str, data: bytes, now_ns: int) -> None:
        calls.append(direction)
        if len(calls) == 1:
            raise OSError("log disk full")

    net.vehicle.packet_taps.append(tap)
    net.advance(2.0)
    assert net.vehicle.endpoint.faults.counts() == {"I/O round: OSError": 1}
    assert hold_is_obeyed(net, app)


def test_malformed_manual_control_and_set_mode_are_dropped_and_counted(
        net: Net, app: FakeApp) -> None:
    net.ground.send(mavlink.MAVLink_manual_control_message(1, 5000, 0, 0, 0, 0),
                    mavlink.MAVLink_manual_control_message(1, 0, -1001, 0, 0, 0),
                    mavlink.MAVLink_set_mode_message(1, CUSTOM, 99),
                    mavlink.MAVLink_manual_control_message(1, 1000, 0x7FFF, 0, -1000, 0))
    status = sys_status(net)
    ((x, y, z, r, buttons, _),) = app.called("manual_control")
    assert (x, z, r, buttons) == (1.0, 0.0, -1.0, 0) and math.isnan(y)
    assert app.called("set_mode") == []
    assert status.errors_count2 == net.vehicle.endpoint.stats().refused == 3


def test_refusals_of_every_protocol_are_counted(net: Net, app: FakeApp) -> None:
    send_item(net, mavlink.MAV_FRAME_MISSION, math.nan, 0.0)  # MISSION_ACK error
    net.ground.send(mavlink.MAVLink_param_set_message(1, 1, b"CTL_SPEED", math.inf,
                                                      mavlink.MAV_PARAM_TYPE_REAL32))
    net.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, 0, 0, 0, 0, 0, math.inf)  # DENIED
    net.command(31999)  # UNSUPPORTED
    assert net.vehicle.endpoint.stats().refused == 4
    assert sys_status(net).errors_count2 == 4


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.randoms(use_true_random=False), st.integers(1, 40))
def test_random_messages_of_every_handled_id_raise_in_no_handler(
        rng: random.Random, count: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        files = VehicleFiles(root / "memory", root / "upload", root / "params.json")
        endpoint = VehicleEndpoint(FakeApp(), VmnavConfig(), files)
        ground = make_codec(255, 190)
        for i in range(count):
            msg = random_message(rng, rng.choice(HANDLED_MESSAGES), VEHICLE)
            now_ns = i * 100_000_000
            endpoint.receive(ground.pack(msg), now_ns, datagram=True)
            endpoint.poll(now_ns)
        endpoint.close()
        assert endpoint.stats().handler_faults == {}
