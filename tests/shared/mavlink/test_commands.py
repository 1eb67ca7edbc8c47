"""Command protocol, both ends through bytes.

The vehicle: every COMMAND_LONG / COMMAND_INT gets a COMMAND_ACK. The ground station:
ACKs, resends with rising confirmation, IN_PROGRESS, time-outs.
"""

from __future__ import annotations

import math
import random
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import LocalProtocolError
from shared.mavlink.address import Address, is_for
from shared.mavlink.commands.gcs import CommandClient, CommandDone, CommandTimedOut, result_name
from shared.mavlink.commands.intervals import MessageIntervals
from shared.mavlink.commands.vehicle import (
    CAPABILITIES,
    CommandDispatcher,
    autopilot_version_message,
    vehicle_handlers,
)
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.modes import Mode
from tests.shared.mavlink.link import GCS, VEHICLE
from tools.bench.hostile_messages import random_message

NAN = math.nan
HEARTBEAT, HOME = mavlink.MAVLINK_MSG_ID_HEARTBEAT, mavlink.MAVLINK_MSG_ID_HOME_POSITION


class Robot:
    """The application side: records what the handlers asked for."""

    def __init__(self) -> None:
        self.calls: list[tuple[Any, ...]] = []
        self.home: Message | None = None
        self.intervals = MessageIntervals({HEARTBEAT: 1_000_000_000,
                                           mavlink.MAVLINK_MSG_ID_ATTITUDE: 200_000_000})
        self.dispatcher = CommandDispatcher(VEHICLE, vehicle_handlers(
            set_mode=lambda mode: self._call("mode", mode),
            start_mission=lambda first, last: self._call("start", first, last),
            set_mission_current=lambda seq: self._call("current", seq),
            arm=lambda arm, force: self._call("arm", arm, force),
            messages={mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION:
                      lambda: autopilot_version_message(uid=0xC0FFEE),
                      HOME: lambda: self.home},
            intervals=self.intervals,
        ))
        self.ground, self.vehicle = make_codec(255, 190), make_codec(1, 1)

    def _call(self, *what: Any) -> int:
        self.calls.append(what)
        return mavlink.MAV_RESULT_ACCEPTED

    def exchange(self, msg: Message) -> list[Message]:
        """Send ``msg`` from the ground; return what the ground decodes of the answer."""
        (received,) = self.vehicle.parse(self.ground.pack(msg))
        return [reply for out in self.dispatcher.handle_message(received)
                for reply in self.ground.parse(self.vehicle.pack(out))]

    def command(self, command: int, *params: float, confirmation: int = 0) -> list[Message]:
        p = list(params) + [NAN] * (7 - len(params))
        return self.exchange(mavlink.MAVLink_command_long_message(1, 1, command, confirmation, *p))


def ack_of(replies: list[Message]) -> tuple[int, int]:
    ack = replies[0]
    assert ack.get_type() == "COMMAND_ACK"
    assert (ack.target_system, ack.target_component) == (GCS.system_id, GCS.component_id)
    return ack.command, ack.result


def test_every_unknown_command_is_unsupported() -> None:
    robot = Robot()
    unknown = [c for c in mavlink.enums["MAV_CMD"] if c not in robot.dispatcher.handlers
               and c != mavlink.MAV_CMD_ENUM_END]
    assert mavlink.MAV_CMD_REQUEST_PROTOCOL_VERSION in unknown and len(unknown) > 150
    for command in unknown:
        replies = robot.command(command, 1.0)
        assert len(replies) == 1 and ack_of(replies) == (command, mavlink.MAV_RESULT_UNSUPPORTED)
    assert robot.calls == []


def test_do_set_mode_in_both_encodings() -> None:
    robot = Robot()
    assert ack_of(robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 4, 0)) == (
        176, mavlink.MAV_RESULT_ACCEPTED)
    assert ack_of(robot.command(mavlink.MAV_CMD_DO_SET_MODE, 129, 4, 4))[1] == 0  # MAVSDK mission
    assert ack_of(robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 11, 0))[1] == (
        mavlink.MAV_RESULT_DENIED)
    assert robot.calls == [("mode", Mode.HOLD), ("mode", Mode.AUTO)]


def test_command_int_is_dispatched_too() -> None:
    robot = Robot()
    replies = robot.exchange(mavlink.MAVLink_command_int_message(
        1, 1, 0, mavlink.MAV_CMD_DO_SET_MODE, 0, 0, 1, 15, 0, 0, 0, 0, 0.0))
    assert ack_of(replies) == (176, mavlink.MAV_RESULT_ACCEPTED)
    assert robot.calls == [("mode", Mode.GUIDED)]


def test_autopilot_version_by_request_message_and_legacy_command() -> None:
    robot = Robot()
    for replies in (robot.command(mavlink.MAV_CMD_REQUEST_MESSAGE, 148),
                    robot.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)):
        assert ack_of(replies)[1] == mavlink.MAV_RESULT_ACCEPTED
        version = replies[1]  # ACK first, then the message
        assert version.get_type() == "AUTOPILOT_VERSION" and version.uid == 0xC0FFEE
        assert version.capabilities == CAPABILITIES | mavlink.MAV_PROTOCOL_CAPABILITY_FTP
    assert ack_of(robot.command(mavlink.MAV_CMD_REQUEST_MESSAGE, 33))[1] == (
        mavlink.MAV_RESULT_DENIED)


def test_home_position_is_denied_until_known() -> None:
    robot = Robot()
    replies = robot.command(mavlink.MAV_CMD_GET_HOME_POSITION)
    assert len(replies) == 1 and ack_of(replies)[1] == mavlink.MAV_RESULT_DENIED
    robot.home = mavlink.MAVLink_home_position_message(0, 0, 0, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)
    for replies in (robot.command(mavlink.MAV_CMD_GET_HOME_POSITION),
                    robot.command(mavlink.MAV_CMD_REQUEST_MESSAGE, HOME)):
        assert ack_of(replies)[1] == mavlink.MAV_RESULT_ACCEPTED
        assert replies[1].get_type() == "HOME_POSITION"


def test_set_message_interval() -> None:
    robot = Robot()
    interval = mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
    assert ack_of(robot.command(interval, HEARTBEAT, 500_000))[1] == mavlink.MAV_RESULT_ACCEPTED
    assert robot.intervals.interval_ns(HEARTBEAT) == 500_000_000
    assert ack_of(robot.command(interval, HEARTBEAT, 1000))[1] == mavlink.MAV_RESULT_ACCEPTED
    assert robot.intervals.interval_ns(HEARTBEAT) == 50_000_000  # floored: 20 Hz at most
    robot.command(interval, HEARTBEAT, -1)
    assert robot.intervals.interval_ns(HEARTBEAT) is None
    robot.command(interval, HEARTBEAT, 0)
    assert robot.intervals.interval_ns(HEARTBEAT) == 1_000_000_000
    for bad in ((245, 1_000_000), (HEARTBEAT, -5), (NAN, 0)):  # EXTENDED_SYS_STATE: not streamed
        assert ack_of(robot.command(interval, *bad))[1] == mavlink.MAV_RESULT_DENIED


def test_arm_mission_start_and_set_current() -> None:
    robot = Robot()
    robot.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    robot.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 21196)
    assert ack_of(robot.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0.5))[1] == (
        mavlink.MAV_RESULT_DENIED)
    robot.command(mavlink.MAV_CMD_MISSION_START)  # MAVSDK: NaN = whole mission
    robot.command(mavlink.MAV_CMD_MISSION_START, 2, 4)
    robot.command(mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 3)
    assert ack_of(robot.command(mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, NAN))[1] == (
        mavlink.MAV_RESULT_DENIED)
    assert robot.calls == [("arm", True, False), ("arm", False, True), ("start", 0, None),
                           ("start", 2, 4), ("current", 3)]


def test_resent_command_is_answered_without_running_twice() -> None:
    robot = Robot()
    first = robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 10, NAN)
    again = robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 10, NAN, confirmation=1)
    assert ack_of(first) == ack_of(again)
    assert robot.calls == [("mode", Mode.AUTO)]
    robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 10, NAN)  # confirmation 0: a new command
    assert robot.calls == [("mode", Mode.AUTO)] * 2


@pytest.mark.parametrize("target", [(2, 1), (1, 191)])
def test_commands_for_others_get_no_answer(target: tuple[int, int]) -> None:
    robot = Robot()
    assert robot.exchange(mavlink.MAVLink_command_long_message(
        *target, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, 4, 0, 0, 0, 0, 0)) == []
    assert robot.exchange(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3)) == []
    assert robot.calls == []


def test_broadcast_commands_are_answered() -> None:
    robot = Robot()
    replies = robot.exchange(mavlink.MAVLink_command_long_message(
        0, 0, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, 4, 0, 0, 0, 0, 0))
    assert ack_of(replies)[1] == mavlink.MAV_RESULT_ACCEPTED
    assert Address(*[replies[0].target_system, replies[0].target_component]) == GCS


def test_infinite_param_or_unknown_frame_is_denied_before_the_handler() -> None:
    robot = Robot()
    inf = math.inf
    assert ack_of(robot.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 4, -inf))[1] == \
        mavlink.MAV_RESULT_DENIED
    assert ack_of(robot.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, NAN, NAN, NAN, NAN,
                                NAN, inf))[1] == mavlink.MAV_RESULT_DENIED
    assert ack_of(robot.exchange(mavlink.MAVLink_command_int_message(
        1, 1, 200, mavlink.MAV_CMD_DO_SET_MODE, 0, 0, 1, 4, 0, 0, 0, 0, 0)))[1] == \
        mavlink.MAV_RESULT_DENIED
    assert ack_of(robot.command(31999, inf))[1] == mavlink.MAV_RESULT_UNSUPPORTED
    assert robot.calls == []


@settings(derandomize=True, max_examples=150, deadline=None)
@given(st.randoms(use_true_random=False),
       st.sampled_from([mavlink.MAVLink_command_long_message,
                        mavlink.MAVLink_command_int_message]))
def test_random_commands_get_one_ack_and_infinite_params_never_reach_a_handler(
        rng: random.Random, cls: type[Message]) -> None:
    robot = Robot()
    msg = random_message(rng, cls, VEHICLE)
    replies = robot.exchange(msg)
    if not is_for(msg, VEHICLE):
        assert replies == []
        return
    assert replies[0].get_type() == "COMMAND_ACK" and replies[0].command == msg.command
    assert [m.get_type() for m in replies].count("COMMAND_ACK") == 1
    params = ([msg.param1, msg.param2, msg.param3, msg.param4, msg.z]
              if cls is mavlink.MAVLink_command_int_message
              else [getattr(msg, f"param{i}") for i in range(1, 8)])
    if any(math.isinf(p) for p in params):
        assert replies[0].result in (mavlink.MAV_RESULT_DENIED, mavlink.MAV_RESULT_UNSUPPORTED)
        assert robot.calls == []


# -- the ground station's end -------------------------------------------------------

CMD = mavlink.MAV_CMD_DO_SET_MODE


def ack(result: int, system_id: int = 1, command: int = CMD) -> Message:
    """A COMMAND_ACK from (``system_id``, 1) to the station, as the station decodes it."""
    (msg,) = make_codec(255, 190).parse(make_codec(system_id, 1).pack(
        mavlink.MAVLink_command_ack_message(command, result, target_system=255,
                                            target_component=190)))
    return msg


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
