"""The page's requests over the WebSocket, checked before anything is sent (pure).

A request is one JSON object::

    {"id": 7, "cmd": "goto", "system": 1, "key": 12}

``id`` (optional, an integer) comes back in the reply; ``system`` (optional) is the
vehicle's system id, the one selected last when absent. Each command's other fields:

=============  ==============================================================
``select``     -- (aim the station at ``system``; faster servo and odometry streams)
``mode``       ``mode``: ``"MANUAL"``, ``"HOLD"``, ``"AUTO"`` or ``"GUIDED"``
``arm``        --
``hold``       -- (mode HOLD)
``estop``      -- (the forced disarm of ``vmnav ground stop``)
``goto``       ``key``: key image id, 0..2^24
``mission``    ``keys``: 1 to 64 key image ids (goals visited in order)
``route``      ``key``: the key images the robot would pass to get there
``params``     -- (every parameter)
``param_set``  ``name``: up to 16 characters; ``value``: a finite number
``teach_start`` ``name``: the path's name (up to 21 printable ASCII characters)
``teach_stop`` --
``teleop``     ``on``: true or false (drive from this page, in MANUAL)
``drive``      ``x`` forward, ``r`` yaw clockwise: numbers in -1..1
``memory``     ``refresh`` (optional): fetch the manifest again
``camera``     ``refresh`` (optional): ask the vehicle's camera for its stream again
=============  ==============================================================

Anything else (not JSON, not an object, an unknown command, a missing or out-of-range
field) raises :class:`~shared.errors.InputError` with one line naming the field.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

from shared.errors import InputError
from shared.mavlink.commands.user import params_from_name
from shared.mavlink.mission.goal import MAX_ID
from shared.mavlink.modes import Mode

#: The longest request accepted, characters (the longest real one is about 100).
MAX_REQUEST_CHARS = 4096
#: MAVLink parameter names are at most 16 characters (common.xml PARAM_SET).
PARAM_NAME_CHARS = 16
#: Largest MAVLink system id.
MAX_SYSTEM_ID = 255
#: Most goals in one mission from the page.
MAX_GOALS = 64

_NO_ARGS = frozenset({"select", "arm", "hold", "estop", "params", "teach_stop"})
COMMANDS = frozenset({*_NO_ARGS, "mode", "goto", "mission", "route", "param_set",
                      "teach_start", "teleop", "drive", "memory", "camera"})


@dataclass(frozen=True, slots=True)
class Request:
    """A checked request.

    Attributes:
        command: one of :data:`COMMANDS`.
        request_id: the page's id for the reply; None if it gave none.
        system_id: the vehicle; None for the one selected last.
        args: the command's fields, checked and converted (``mode`` is a :class:`Mode`).
    """

    command: str
    request_id: int | None = None
    system_id: int | None = None
    args: dict[str, Any] = field(default_factory=dict)


def _int(data: dict[str, Any], name: str, low: int, high: int) -> int:
    value = data.get(name)
    if type(value) is not int or not low <= value <= high:
        raise InputError(name, f"expected an integer in {low}..{high}, got {value!r}")
    return value


def _number(data: dict[str, Any], name: str, low: float = -math.inf,
            high: float = math.inf) -> float:
    value = data.get(name)
    if type(value) not in (int, float) or not (math.isfinite(value) and low <= value <= high):
        span = f" in {low:g}..{high:g}" if math.isfinite(low) else ""
        raise InputError(name, f"expected a finite number{span}, got {value!r}")
    return float(value)


def _text(data: dict[str, Any], name: str, max_chars: int) -> str:
    value = data.get(name)
    if not isinstance(value, str) or len(value) > max_chars:
        raise InputError(name, f"expected text of at most {max_chars} characters, "
                               f"got {value!r:.40}")
    return value


def request_id_of(text: str) -> int | None:
    """The ``id`` of a request that fails :func:`parse_request`, if one can be read, so the
    page can match the error to what it sent."""
    try:
        data = json.loads(text)
    except ValueError:
        return None
    value = data.get("id") if isinstance(data, dict) else None
    return value if type(value) is int else None


def parse_request(text: str) -> Request:
    """Check one request (module docstring).

    Raises:
        InputError: not a valid request; one line naming the field at fault.
    """
    if len(text) > MAX_REQUEST_CHARS:
        raise InputError("request", f"{len(text)} characters, at most {MAX_REQUEST_CHARS}")
    try:
        data = json.loads(text)
    except ValueError as e:
        raise InputError("request", f"not JSON ({e})") from None
    if not isinstance(data, dict):
        raise InputError("request", f"expected a JSON object, got {type(data).__name__}")
    request_id = _int(data, "id", -2**53, 2**53) if "id" in data else None
    system_id = _int(data, "system", 1, MAX_SYSTEM_ID) if "system" in data else None
    command = data.get("cmd")
    if command not in COMMANDS:
        raise InputError("cmd", f"unknown command {command!r:.40} (known: "
                                f"{', '.join(sorted(COMMANDS))})")
    args: dict[str, Any] = {}
    if command == "mode":
        name = data.get("mode")
        if name not in Mode.__members__:
            raise InputError("mode", f"unknown mode {name!r:.40} (known: "
                                     f"{', '.join(Mode.__members__)})")
        args["mode"] = Mode[name]
    elif command in ("goto", "route"):
        args["key"] = _int(data, "key", 0, MAX_ID)
    elif command == "mission":
        keys = data.get("keys")
        if not isinstance(keys, list) or not 1 <= len(keys) <= MAX_GOALS:
            raise InputError("keys", f"expected a list of 1 to {MAX_GOALS} key image ids, "
                                     f"got {keys!r:.40}")
        args["keys"] = tuple(_int({"keys": k}, "keys", 0, MAX_ID) for k in keys)
    elif command == "param_set":
        args["name"] = _text(data, "name", PARAM_NAME_CHARS)
        args["value"] = _number(data, "value")
    elif command == "teach_start":
        args["name"] = _text(data, "name", 64)
        try:
            params_from_name(args["name"])
        except ValueError as e:
            raise InputError("name", str(e)) from None
    elif command == "teleop":
        if type(data.get("on")) is not bool:
            raise InputError("on", f"expected true or false, got {data.get('on')!r:.40}")
        args["on"] = data["on"]
    elif command == "drive":
        args["x"] = _number(data, "x", -1.0, 1.0)
        args["r"] = _number(data, "r", -1.0, 1.0)
    elif command in ("memory", "camera"):
        args["refresh"] = bool(data.get("refresh", False))
    return Request(command, request_id, system_id, args)
