"""CommandClient: ACKs, resends with rising confirmation, IN_PROGRESS, time-outs."""

from __future__ import annotations

import math

import pytest

from ground.command_client import CommandClient, CommandDone, CommandTimedOut, result_name
from shared.errors import LocalProtocolError
from shared.mavlink.address import Address
from shared.mavlink.dialect import mavlink
from tests.ground.messages import from_system

GCS, VEHICLE = Address(255, 190), Address(1, 1)
CMD = mavlink.MAV_CMD_DO_SET_MODE


def ack(result: int, system_id: int = 1, command: int = CMD) -> object:
    return from_system(system_id, mavlink.MAVLink_command_ack_message(
        command, result, target_system=255, target_component=190))[0]


def test_ack_ends_the_command() -> None:
    client = CommandClient(GCS, VEHICLE)
    [sent] = client.send(CMD, (1.0, 4.0), 0)
    assert (sent.target_system, sent.command, sent.confirmation, sent.param2) == (1, CMD, 0, 4.0)
    assert math.isnan(sent.param3)
    client.handle_message(ack(mavlink.MAV_RESULT_ACCEPTED, system_id=2), 1)  # another vehicle
    client.handle_message(ack(mavlink.MAV_RESULT_ACCEPTED, command=CMD + 1), 1)  # another command
    assert client.busy and client.next_event() is None
    client.handle_message(ack(mavlink.MAV_RESULT_DENIED), 2)
    assert client.next_event() == CommandDone(CMD, mavlink.MAV_RESULT_DENIED)
    assert not client.busy and client.get_timer() is None
    assert result_name(mavlink.MAV_RESULT_DENIED) == "MAV_RESULT_DENIED"


def test_resends_then_times_out() -> None:
    client = CommandClient(GCS, VEHICLE, timeout_ns=100, retries=2)
    client.send(CMD, (), 0)
    assert client.handle_timer(99) == []
    assert [m.confirmation for m in client.handle_timer(100)] == [1]
    assert [m.confirmation for m in client.handle_timer(200)] == [2]
    assert client.handle_timer(300) == []
    assert client.next_event() == CommandTimedOut(CMD, 3)


def test_in_progress_waits_without_resending() -> None:
    client = CommandClient(GCS, VEHICLE, timeout_ns=100, retries=5)
    client.send(CMD, (), 0)
    client.handle_message(ack(mavlink.MAV_RESULT_IN_PROGRESS), 50)
    assert client.get_timer() == 150 and client.next_event() is None
    assert client.handle_timer(150) == []
    assert client.next_event() == CommandTimedOut(CMD, 1)


def test_one_command_at_a_time() -> None:
    client = CommandClient(GCS, VEHICLE)
    client.send(CMD, (), 0)
    with pytest.raises(LocalProtocolError, match="waits for its ACK"):
        client.send(CMD, (), 0)
