"""Vehicle modes: our numbering, decoding mode requests, and the HEARTBEAT that reports them.

Our ``custom_mode`` numbers are ArduRover's (reference/mavlink-vehicle.md sec. 1.1),
so MAVProxy and Mission Planner show meaningful names for free: pymavlink decodes
``custom_mode`` with the ArduPilot table for the MAV_TYPE whenever the autopilot is
not PX4, and we report ``MAV_TYPE_GROUND_ROVER`` with ``MAV_AUTOPILOT_GENERIC``.

Mode requests come in two encodings:

* **ArduPilot** (MAVProxy ``mode HOLD``, Mission Planner): ``DO_SET_MODE`` with
  param1 = base mode (CUSTOM_MODE_ENABLED set), param2 = the custom mode number;
  ``SET_MODE`` with ``custom_mode`` = the number.
* **PX4** (MAVSDK for every non-ArduPilot autopilot, ``SystemImpl::make_command_px4_mode``):
  ``DO_SET_MODE`` with param2 = PX4 main mode, param3 = PX4 sub mode; in
  ``SET_MODE.custom_mode`` the main mode is byte 2 and the sub mode byte 3 (PX4's
  ``px4_custom_mode`` union: ``reserved:u16 | main_mode:u8 | sub_mode:u8``).
  MAVSDK sends Hold = (AUTO 4, LOITER 3), Mission = (AUTO 4, MISSION 4) and
  Manual = (MANUAL 1, 0).

The encodings overlap: (4, 0) is ArduRover HOLD, and (1, 0) is both ArduRover ACRO
and PX4 MANUAL. A non-zero sub mode means PX4; otherwise our ArduRover numbers
win, and what is left of PX4's main-only modes (MANUAL) is tried next. So a
MAVProxy ``mode ACRO`` selects MANUAL, the closest mode we have.
"""

from __future__ import annotations

import enum
import math

from shared.mavlink.dialect import mavlink


class Mode(enum.IntEnum):
    """The robot's modes, numbered as ArduRover's ``custom_mode``."""

    MANUAL = 0  #: operator drives (teach); no autonomous motion
    HOLD = 4  #: stopped, mission kept
    AUTO = 10  #: repeat the mission in force, goal after goal
    GUIDED = 15  #: go to one goal given outside the mission


#: PX4 main modes and AUTO sub modes we accept (PX4 ``px4_custom_mode.h``).
PX4_MAIN_MANUAL = 1
PX4_MAIN_AUTO = 4
PX4_SUB_AUTO_LOITER = 3
PX4_SUB_AUTO_MISSION = 4

_NUMBERS = frozenset(int(m) for m in Mode)

_PX4_MODES: dict[tuple[int, int], Mode] = {
    (PX4_MAIN_MANUAL, 0): Mode.MANUAL,
    (PX4_MAIN_AUTO, PX4_SUB_AUTO_LOITER): Mode.HOLD,
    (PX4_MAIN_AUTO, PX4_SUB_AUTO_MISSION): Mode.AUTO,
}

_BASE_MODE_FLAGS: dict[Mode, int] = {
    Mode.MANUAL: 0,
    Mode.HOLD: 0,
    Mode.AUTO: mavlink.MAV_MODE_FLAG_AUTO_ENABLED,
    Mode.GUIDED: mavlink.MAV_MODE_FLAG_GUIDED_ENABLED,
}


def _as_int(value: float) -> int | None:
    """A float command parameter as an int; NaN (MAVSDK's "not set") is 0; None if fractional."""
    if math.isnan(value):
        return 0
    if not math.isfinite(value) or value != int(value):
        return None
    return int(value)


def mode_from_numbers(main: int, sub: int) -> Mode | None:
    """Our mode for a (main, sub) pair in either encoding; None if it names none of ours.

    Args:
        main: ArduRover custom mode number, or PX4 main mode.
        sub: PX4 sub mode; 0 when the sender used ArduPilot numbering.
    """
    if sub == 0 and main in _NUMBERS:
        return Mode(main)
    return _PX4_MODES.get((main, sub))


def mode_from_command(param1: float, param2: float, param3: float) -> Mode | None:
    """Decode ``MAV_CMD_DO_SET_MODE`` (176) parameters.

    Args:
        param1: base mode; must have ``MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`` (other
            flags, e.g. SAFETY_ARMED from MAVSDK, are ignored).
        param2: custom mode (ArduPilot) or PX4 main mode.
        param3: PX4 sub mode; 0 or NaN for ArduPilot senders.

    Returns:
        The requested mode, or None when the request names no mode of ours.
    """
    base, main, sub = _as_int(param1), _as_int(param2), _as_int(param3)
    if base is None or main is None or sub is None:
        return None
    if not base & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return None
    return mode_from_numbers(main, sub)


def mode_from_set_mode(base_mode: int, custom_mode: int) -> Mode | None:
    """Decode a ``SET_MODE`` (11) message's fields.

    Args:
        base_mode: must have ``MAV_MODE_FLAG_CUSTOM_MODE_ENABLED``.
        custom_mode: our number (< 65536), or PX4's main mode in byte 2 and sub mode
            in byte 3.
    """
    if not base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
        return None
    if custom_mode <= 0xFFFF:
        return mode_from_numbers(custom_mode, 0)
    if custom_mode & 0xFFFF:
        return None
    return mode_from_numbers((custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF)


def base_mode_flags(mode: Mode, armed: bool) -> int:
    """HEARTBEAT ``base_mode``: CUSTOM_MODE_ENABLED, SAFETY_ARMED when the motors are
    enabled, AUTO_ENABLED in AUTO, GUIDED_ENABLED in GUIDED (reference sec. 1.1)."""
    flags = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | _BASE_MODE_FLAGS[mode]
    if armed:
        flags |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    return flags


def heartbeat_message(mode: Mode, armed: bool,
                      system_status: int) -> mavlink.MAVLink_heartbeat_message:
    """The vehicle's HEARTBEAT: a generic-autopilot ground rover in ``mode``.

    Args:
        mode: the current mode, sent as ``custom_mode``.
        armed: whether the motors are enabled.
        system_status: a ``MAV_STATE``: BOOT while starting, STANDBY when idle,
            ACTIVE while driving, CRITICAL/EMERGENCY on failures.
    """
    return mavlink.MAVLink_heartbeat_message(
        type=mavlink.MAV_TYPE_GROUND_ROVER,
        autopilot=mavlink.MAV_AUTOPILOT_GENERIC,
        base_mode=base_mode_flags(mode, armed),
        custom_mode=int(mode),
        system_status=system_status,
        mavlink_version=3,
    )
