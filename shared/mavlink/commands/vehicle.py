"""The command protocol, vehicle side (devguide command.md): every command gets a COMMAND_ACK.

Theory of operation
-------------------

:class:`CommandDispatcher` turns COMMAND_LONG and COMMAND_INT addressed to the
vehicle into a :class:`CommandRequest`, looks the command id up in its handler
table and answers with COMMAND_ACK (addressed back to the sender), followed by
whatever messages the handler returned (ACK first, then the message: the
specification's order for REQUEST_MESSAGE). A command without a handler gets
``MAV_RESULT_UNSUPPORTED``, never silence (GCSs poll until answered, reference
sec. 0.8), e.g. REQUEST_PROTOCOL_VERSION (519), whose PROTOCOL_VERSION message
pymavlink 2.4.50 lacks.

Parameters are checked before a handler sees them: a command with an infinite
parameter, or a COMMAND_INT in a frame that is no MAV_FRAME, is ``MAV_RESULT_DENIED``
(common.xml: "supported but has invalid parameters"); NaN stays "not set". Handlers
check the rest (whole numbers, ranges) and deny what does not fit.

A COMMAND_LONG resent because our ACK was lost arrives with ``confirmation`` > 0;
if it repeats the last command from that sender it is answered from the cache
and not executed twice (reference sec. 1.3).

:func:`vehicle_handlers` builds the robot's table from the application's
callbacks; each callback returns a ``MAV_RESULT``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.commands.intervals import MessageIntervals
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.mission.items import KNOWN_FRAMES
from shared.mavlink.modes import Mode, mode_from_command

#: COMPONENT_ARM_DISARM param2 that forces arming/disarming (common.xml).
FORCE_ARM_MAGIC = 21196

#: AUTOPILOT_VERSION capability bits we implement (reference sec. 1.2). All
#: parameters are REAL32, so the parameter encoding bit is moot; bytewise is what
#: MAVSDK and QGC use for a generic autopilot anyway.
CAPABILITIES = (mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT
                | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE)


@dataclass(frozen=True, slots=True)
class CommandRequest:
    """A received COMMAND_LONG or COMMAND_INT.

    ``params`` are param1..param7; for COMMAND_INT, param5/param6 are its int32
    ``x``/``y`` (exact as floats) and param7 its ``z``. MAVSDK sends NaN for
    unused params: handlers treat NaN as "not set".
    """

    command: int
    params: tuple[float, float, float, float, float, float, float]
    source: Address
    confirmation: int = 0  #: 0 on first transmission; COMMAND_INT has none
    frame: int | None = None  #: COMMAND_INT's MAV_FRAME; None for COMMAND_LONG


@dataclass(frozen=True, slots=True)
class CommandReply:
    """A handler's answer: the ACK result and the messages to send after the ACK."""

    result: int  #: a MAV_RESULT
    messages: tuple[Message, ...] = ()
    progress: int = 0  #: the ACK's ``progress`` (0-100, 255 unknown) for IN_PROGRESS


Handler = Callable[[CommandRequest], CommandReply]


def request_from_message(msg: Any) -> CommandRequest:
    """The request a COMMAND_LONG or COMMAND_INT carries."""
    if isinstance(msg, mavlink.MAVLink_command_int_message):
        params = (msg.param1, msg.param2, msg.param3, msg.param4,
                  float(msg.x), float(msg.y), msg.z)
        return CommandRequest(msg.command, params, source_of(msg), frame=msg.frame)
    params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
    return CommandRequest(msg.command, params, source_of(msg), confirmation=msg.confirmation)


def _malformed(request: CommandRequest) -> bool:
    """An infinite parameter, or a COMMAND_INT frame that is no MAV_FRAME (module docstring)."""
    return (any(math.isinf(p) for p in request.params)
            or (request.frame is not None and request.frame not in KNOWN_FRAMES))


def _cache_key(request: CommandRequest) -> tuple[Any, ...]:
    params = tuple(None if math.isnan(p) else p for p in request.params)
    return (request.source, request.command, params)


class CommandDispatcher:
    """Answers every command addressed to the vehicle.

    Args:
        address: this vehicle, for filtering.
        handlers: command id -> handler; everything else is UNSUPPORTED.
    """

    def __init__(self, address: Address, handlers: Mapping[int, Handler]) -> None:
        self.address = address
        self.handlers = dict(handlers)
        self._last: tuple[tuple[Any, ...], CommandReply] | None = None

    def handle_message(self, msg: Message) -> list[Message]:
        """Answer one received message if it is a command for us; else return []."""
        if not isinstance(msg, mavlink.MAVLink_command_long_message
                          | mavlink.MAVLink_command_int_message) or not is_for(msg, self.address):
            return []
        request = request_from_message(msg)
        key = _cache_key(request)
        if request.confirmation > 0 and self._last is not None and self._last[0] == key:
            reply = self._last[1]
        else:
            handler = self.handlers.get(request.command)
            if handler is None:
                reply = CommandReply(mavlink.MAV_RESULT_UNSUPPORTED)
            elif _malformed(request):
                reply = CommandReply(mavlink.MAV_RESULT_DENIED)
            else:
                reply = handler(request)
            self._last = (key, reply)
        ack = mavlink.MAVLink_command_ack_message(
            request.command, reply.result, reply.progress,
            target_system=request.source.system_id,
            target_component=request.source.component_id)
        return [ack, *reply.messages]


def _param_int(value: float, default: int) -> int | None:
    """A whole-number parameter; NaN gives ``default``; None if fractional or infinite."""
    if math.isnan(value):
        return default
    if not math.isfinite(value) or value != int(value):
        return None
    return int(value)


def autopilot_version_message(uid: int, flight_sw_version: int = 0,
                              ftp: bool = True) -> mavlink.MAVLink_autopilot_version_message:
    """AUTOPILOT_VERSION (148) for this vehicle.

    Args:
        uid: unique per robot (QGC may use it to spot duplicate system ids), 64 bits.
        flight_sw_version: version as MAVLink packs it (major << 24 | minor << 16 | patch << 8).
        ftp: whether the vehicle serves MAVLink FTP (capability bit).
    """
    capabilities = CAPABILITIES | (mavlink.MAV_PROTOCOL_CAPABILITY_FTP if ftp else 0)
    return mavlink.MAVLink_autopilot_version_message(
        capabilities, flight_sw_version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, uid)


def vehicle_handlers(
    *,
    set_mode: Callable[[Mode], int],
    start_mission: Callable[[int, int | None], int],
    set_mission_current: Callable[[int], int],
    arm: Callable[[bool, bool], int],
    messages: Mapping[int, Callable[[], Message | None]],
    intervals: MessageIntervals,
) -> dict[int, Handler]:
    """The robot's command table.

    Args:
        set_mode: DO_SET_MODE (176) decoded by :func:`~shared.mavlink.modes.mode_from_command`
            (either encoding); undecodable requests are DENIED without a call.
        start_mission: MISSION_START (300) with (first item, last item or None).
        set_mission_current: DO_SET_MISSION_CURRENT (224) with the item seq.
        arm: COMPONENT_ARM_DISARM (400) with (arm, forced by param2 = 21196).
        messages: message id -> provider of that message now (None: not available,
            e.g. HOME_POSITION before a home is known). Serves REQUEST_MESSAGE (512),
            REQUEST_AUTOPILOT_CAPABILITIES (520, AUTOPILOT_VERSION) and
            GET_HOME_POSITION (410, HOME_POSITION); unknown or unavailable messages
            are DENIED, and MAVProxy keeps asking for the home until it gets one.
        intervals: SET_MESSAGE_INTERVAL (511).
    """

    def send_message(msg_id: int | None) -> CommandReply:
        provider = messages.get(msg_id) if msg_id is not None else None
        msg = provider() if provider is not None else None
        if msg is None:
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return CommandReply(mavlink.MAV_RESULT_ACCEPTED, (msg,))

    def do_set_mode(r: CommandRequest) -> CommandReply:
        mode = mode_from_command(*r.params[:3])
        return CommandReply(mavlink.MAV_RESULT_DENIED if mode is None else set_mode(mode))

    def mission_start(r: CommandRequest) -> CommandReply:
        first, last = _param_int(r.params[0], 0), _param_int(r.params[1], -1)
        if first is None or last is None or first < 0:
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return CommandReply(start_mission(first, last if last >= 0 else None))

    def mission_current(r: CommandRequest) -> CommandReply:
        seq = _param_int(r.params[0], -1)
        if seq is None or seq < 0:
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return CommandReply(set_mission_current(seq))

    def arm_disarm(r: CommandRequest) -> CommandReply:
        if r.params[0] not in (0.0, 1.0):
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return CommandReply(arm(r.params[0] == 1.0, r.params[1] == FORCE_ARM_MAGIC))

    def capabilities(r: CommandRequest) -> CommandReply:
        if r.params[0] != 1.0:
            return CommandReply(mavlink.MAV_RESULT_DENIED)
        return send_message(mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION)

    return {
        mavlink.MAV_CMD_DO_SET_MODE: do_set_mode,
        mavlink.MAV_CMD_MISSION_START: mission_start,
        mavlink.MAV_CMD_DO_SET_MISSION_CURRENT: mission_current,
        mavlink.MAV_CMD_COMPONENT_ARM_DISARM: arm_disarm,
        mavlink.MAV_CMD_REQUEST_MESSAGE: lambda r: send_message(_param_int(r.params[0], -1)),
        mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: capabilities,
        mavlink.MAV_CMD_GET_HOME_POSITION:
            lambda r: send_message(mavlink.MAVLINK_MSG_ID_HOME_POSITION),
        mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            lambda r: CommandReply(intervals.set_interval(r.params[0], r.params[1])),
    }
