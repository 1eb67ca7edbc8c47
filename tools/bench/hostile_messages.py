"""Hostile MAVLink messages against a live vehicle (issue 15, items 1 and 2): :func:`measure`.

The vehicle is a real process (:mod:`tools.bench.link_vehicles`: a
:class:`~robot.vehicle.endpoint.VehicleEndpoint` on a
:class:`~robot.vehicle.udp_vehicle.UdpVehicle` with its own I/O thread, the kinematic
:class:`~tools.bench.link_load.LinkLoadApp` as its robot, whose missions drive at
0.2 m/s). It sends to a :class:`~ground.station.GroundStation` here, on a real socket.
A second socket here, a stranger spoofing the station's ids (255/190, as anyone on an
unsigned link can), sends the attack:

1. the issue's packets, each a MISSION_COUNT then a deprecated MISSION_ITEM (id 39):
   x = NaN, x = +inf, y = -inf, and x = 1000 deg in a global frame (:data:`ISSUE_ITEMS`);
   each must get its MISSION_ACK error;
2. with a goal mission uploaded and running (AUTO), a MISSION_COUNT: it must get
   MAV_MISSION_DENIED before any item is requested;
3. :data:`RANDOM_MESSAGES` messages of every id the vehicle handles
   (:data:`HANDLED_MESSAGES`) with random field values (:func:`random_message`,
   seeded), in bursts of :data:`BURST` every :data:`BURST_PERIOD_S`.

Then the station commands HOLD, waits for the next heartbeat and watches for
:data:`AFTER_S` more. Figures: packets sent, handler exceptions (SYS_STATUS
``errors_count1``) and messages refused (``errors_count2``), whether the I/O thread
still beats after the HOLD, whether HOLD was obeyed (ACK and heartbeat), and the
heartbeat rate the station received from the first attack packet to the end. Takes
about 15 s (the vehicle process starts in 2-5 s of it).
"""

from __future__ import annotations

import math
import random
import socket
from typing import Any

from ground.fleet import VehicleState
from ground.station import GroundError, GroundStation
from robot.vehicle.robot_params import ROBOT_PARAMS
from shared.clock import NS_PER_S, WallClock
from shared.mavlink.address import Address
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.mission.goal import GOAL_COMMAND, Goal
from shared.mavlink.mission.items import KNOWN_FRAMES, mission_result_name
from shared.mavlink.modes import Mode
from tools.bench.link_load import make_load_app
from tools.bench.link_vehicles import VehicleProcesses

#: Every message class the vehicle endpoint acts on.
HANDLED_MESSAGES: tuple[type[Message], ...] = (
    mavlink.MAVLink_heartbeat_message, mavlink.MAVLink_set_mode_message,
    mavlink.MAVLink_param_request_read_message, mavlink.MAVLink_param_request_list_message,
    mavlink.MAVLink_param_set_message, mavlink.MAVLink_mission_item_message,
    mavlink.MAVLink_mission_request_message, mavlink.MAVLink_mission_set_current_message,
    mavlink.MAVLink_mission_request_list_message, mavlink.MAVLink_mission_count_message,
    mavlink.MAVLink_mission_clear_all_message, mavlink.MAVLink_mission_ack_message,
    mavlink.MAVLink_mission_request_int_message, mavlink.MAVLink_manual_control_message,
    mavlink.MAVLink_mission_item_int_message, mavlink.MAVLink_command_int_message,
    mavlink.MAVLink_command_long_message, mavlink.MAVLink_file_transfer_protocol_message,
    mavlink.MAVLink_timesync_message,
)
#: The commands the vehicle has handlers for, and the goal item's: a random ``command``
#: is one of these most of the time, so that it reaches a handler.
COMMANDS = (
    mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_CMD_MISSION_START,
    mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
    mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
    mavlink.MAV_CMD_GET_HOME_POSITION, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
    GOTO_PHOTO, TEACH_START, TEACH_STOP, GOAL_COMMAND,
)
#: Floats a random field takes half of the time: not finite, huge, edges of ranges.
SPECIAL_FLOATS = (math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, 1e10, -1.0, 0.0, 0.5,
                  1.0, 1000.0, 2.0**24, 2.0**31)
#: The issue's MISSION_ITEMs: name -> (frame, x, y, the MISSION_ACK result it must get);
#: each follows a MISSION_COUNT of 1.
ISSUE_ITEMS: dict[str, tuple[int, float, float, str]] = {
    "x_nan": (mavlink.MAV_FRAME_MISSION, math.nan, 0.0, "MAV_MISSION_INVALID_PARAM5_X"),
    "x_inf": (mavlink.MAV_FRAME_MISSION, math.inf, 0.0, "MAV_MISSION_INVALID_PARAM5_X"),
    "y_minus_inf": (mavlink.MAV_FRAME_LOCAL_NED, 0.0, -math.inf, "MAV_MISSION_INVALID_PARAM6_Y"),
    "global_x_1000_deg": (mavlink.MAV_FRAME_GLOBAL, 1000.0, 8.5, "MAV_MISSION_INVALID_PARAM5_X"),
}
#: Random messages sent, and how: bursts of BURST every BURST_PERIOD_S (500 messages/s).
RANDOM_MESSAGES = 3000
BURST = 10
BURST_PERIOD_S = 0.02
#: How long the station watches after the attack, s.
AFTER_S = 3.0
#: Limits of the whole run's waits, s.
VEHICLE_WAIT_S = 30.0
ANSWER_WAIT_S = 5.0
#: Least heartbeat rate the station must keep receiving, Hz (issue 15, flood target).
MIN_HEARTBEAT_HZ = 0.9
_KEY_IMAGES = 40
_GOAL = Goal(30)  # 15 m along the ring at 0.2 m/s: the mission outlasts the attack
_GCS = Address(255, 190)


def _int_value(rng: random.Random, fieldtype: str) -> int:
    bits = int(fieldtype.removeprefix("u").removeprefix("int").removesuffix("_t"))
    low, high = (-2 ** (bits - 1), 2 ** (bits - 1) - 1) if fieldtype[0] == "i" else (0, 2**bits - 1)
    return rng.choice((low, high, 0, 1, -1 if low else 2, rng.randint(low, high)))


def _float_value(rng: random.Random) -> float:
    if rng.random() < 0.5:
        return rng.choice(SPECIAL_FLOATS)
    return rng.uniform(-1e4, 1e4)


def _field_value(rng: random.Random, name: str, fieldtype: str, length: int,
                 target: Address) -> Any:
    """One random value of field ``name``: the vehicle's address, a handled command, a
    known frame or parameter name most of the time, so that handlers get to see it."""
    aimed = rng.random() < 0.7
    if name == "target_system" or name == "target":
        return target.system_id if aimed else _int_value(rng, fieldtype)
    if name == "target_component":
        return target.component_id if aimed else _int_value(rng, fieldtype)
    if name == "mission_type":
        return mavlink.MAV_MISSION_TYPE_MISSION if aimed else _int_value(rng, fieldtype)
    if name == "command":
        return rng.choice(COMMANDS) if aimed else _int_value(rng, fieldtype)
    if name == "frame":
        return rng.choice(sorted(KNOWN_FRAMES)) if aimed else _int_value(rng, fieldtype)
    if name == "seq":
        return rng.randint(0, 3) if aimed else _int_value(rng, fieldtype)
    if fieldtype == "char":
        if aimed:
            return rng.choice(ROBOT_PARAMS).name.encode("ascii")
        return bytes(rng.randrange(256) for _ in range(rng.randint(0, length)))
    one = _float_value if fieldtype in ("float", "double") else None
    if length:
        if one is not None:
            return [one(rng) for _ in range(length)]
        return [_int_value(rng, fieldtype) for _ in range(length)]
    return one(rng) if one is not None else _int_value(rng, fieldtype)


def random_message(rng: random.Random, cls: type[Message], target: Address) -> Message:
    """A message of class ``cls`` with random field values, aimed at ``target`` most of the
    time (:func:`_field_value`); every value fits its wire type, so it packs."""
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    fields = [_field_value(rng, name, fieldtype, lengths[name], target)
              for name, fieldtype in zip(cls.fieldnames, cls.fieldtypes, strict=True)]
    if cls is mavlink.MAVLink_file_transfer_protocol_message and rng.random() < 0.7:
        fields[3][3] = rng.randint(0, 16)  # the payload's opcode: mostly a real one
    msg: Message = cls(*fields)
    return msg


class _Heard:
    """What the station heard from the vehicle during the run, as a station listener."""

    def __init__(self, station: GroundStation) -> None:
        self._clock = station.clock
        self.heartbeats_ns: list[int] = []  # station clock
        self.mission_acks: list[Any] = []
        self.item_requests = 0  # MISSION_REQUEST and MISSION_REQUEST_INT
        station.listeners.append(self)

    def __call__(self, vehicle: VehicleState, msg: Any) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            self.heartbeats_ns.append(self._clock.now_ns())
        elif kind == "MISSION_ACK":
            self.mission_acks.append(msg)
        elif kind in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):
            self.item_requests += 1


def measure(seed: int = 0) -> dict[str, object]:
    """Run the attack of the module docstring once against a fresh vehicle process.

    Args:
        seed: seeds the random messages.

    Returns:
        ``packets_sent``, ``random_messages``, ``issue_cases`` (case -> the MISSION_ACK
        result it got, or ``"no answer"``), ``upload_while_running`` (its result) and
        ``requests_after_denied`` (items requested anyway), ``handler_exceptions`` and
        ``messages_refused`` (SYS_STATUS errors_count1/2 at the end; -1 unanswered),
        ``thread_alive`` (a heartbeat after the HOLD command), ``hold_obeyed``,
        ``heartbeat_hz`` (from the first attack packet to the end), ``attack_s`` and
        ``targets_met``.
    """
    rng = random.Random(seed)
    clock = WallClock()
    with GroundStation.open("udpin:127.0.0.1:0", clock) as station, \
            VehicleProcesses([1], 1, station.link.local_port, _KEY_IMAGES, make_load_app), \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as stranger:
        vehicle = station.wait_vehicle(VEHICLE_WAIT_S)
        assert vehicle.peer is not None
        heard = _Heard(station)
        spoof = make_codec(_GCS.system_id, _GCS.component_id)
        target = vehicle.address
        ids = (target.system_id, target.component_id)
        sent = 0

        def send(*messages: Message) -> None:
            nonlocal sent
            for msg in messages:
                stranger.sendto(spoof.pack(msg), vehicle.peer)
                sent += 1

        def answer() -> str:
            acks = heard.mission_acks
            count = len(acks)
            got = station.run_until(lambda: len(acks) > count, round(ANSWER_WAIT_S * NS_PER_S))
            return mission_result_name(acks[-1].type) if got else "no answer"

        start_ns = clock.now_ns()
        cases: dict[str, str] = {}
        for name, (frame, x, y, _) in ISSUE_ITEMS.items():
            send(mavlink.MAVLink_mission_count_message(*ids, 1, 0))
            send(mavlink.MAVLink_mission_item_message(
                *ids, 0, frame, GOAL_COMMAND, 0, 1, 3.0, 0, 0, 0, x, y, 0.0, 0))
            cases[name] = answer()
        try:
            station.upload_goals([_GOAL])
            station.start_mission()
        except GroundError as e:  # the vehicle stopped answering: the figures say so
            while_running, asked = f"no mission running: {e}", 0
        else:
            asked = heard.item_requests
            send(mavlink.MAVLink_mission_count_message(*ids, 2, 0))
            while_running = answer()
            asked = heard.item_requests - asked
        for burst in range(0, RANDOM_MESSAGES, BURST):
            send(*(random_message(rng, rng.choice(HANDLED_MESSAGES), target)
                   for _ in range(min(BURST, RANDOM_MESSAGES - burst))))
            station.run_until(lambda: False, round(BURST_PERIOD_S * NS_PER_S))
        attack_s = (clock.now_ns() - start_ns) / NS_PER_S
        try:
            station.set_mode(Mode.HOLD)
            acked = True
        except GroundError:
            acked = False
        ordered_ns = clock.now_ns()
        beats = heard.heartbeats_ns
        alive = station.run_until(lambda: bool(beats) and beats[-1] > ordered_ns,
                                  round(VEHICLE_WAIT_S * NS_PER_S))
        station.run_until(lambda: False, round(AFTER_S * NS_PER_S))
        end_ns = clock.now_ns()
        try:
            status = station.request_message(mavlink.MAVLINK_MSG_ID_SYS_STATUS, ANSWER_WAIT_S)
        except GroundError:  # no answer: the counters are unknown (-1)
            status = None
    heartbeat_hz = sum(start_ns <= t <= end_ns for t in beats) / ((end_ns - start_ns) / NS_PER_S)
    hold = acked and alive and vehicle.mode is Mode.HOLD
    faults = -1 if status is None else int(status.errors_count1)
    refused = -1 if status is None else int(status.errors_count2)
    expected = {name: case[3] for name, case in ISSUE_ITEMS.items()}
    return {
        "packets_sent": sent,
        "random_messages": RANDOM_MESSAGES,
        "issue_cases": cases,
        "upload_while_running": while_running,
        "requests_after_denied": asked,
        "handler_exceptions": faults,
        "messages_refused": refused,
        "thread_alive": alive,
        "hold_obeyed": hold,
        "heartbeat_hz": round(heartbeat_hz, 3),
        "attack_s": round(attack_s, 2),
        "targets_met": (cases == expected and while_running == "MAV_MISSION_DENIED"
                        and asked == 0 and faults == 0 and alive and hold
                        and heartbeat_hz >= MIN_HEARTBEAT_HZ),
    }

