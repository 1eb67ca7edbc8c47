"""Modes: ArduRover numbering, both request encodings, the HEARTBEAT as GCSs decode it."""

from __future__ import annotations

import math

import pytest

from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.modes import (
    Mode,
    base_mode_flags,
    heartbeat_message,
    mode_from_command,
    mode_from_set_mode,
)

CUSTOM = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
ARMED = mavlink.MAV_MODE_FLAG_SAFETY_ARMED


def test_numbers_are_ardurovers() -> None:
    assert {m.name: int(m) for m in Mode} == {"MANUAL": 0, "HOLD": 4, "AUTO": 10, "GUIDED": 15}


@pytest.mark.parametrize("mode", list(Mode))
@pytest.mark.parametrize("param3", [0.0, math.nan])
def test_ardupilot_encoding_of_do_set_mode(mode: Mode, param3: float) -> None:
    """MAVProxy ``mode HOLD`` sends DO_SET_MODE(p1=1, p2=4); MAVSDK leaves unused params NaN."""
    assert mode_from_command(CUSTOM, float(mode), param3) is mode


@pytest.mark.parametrize(("main", "sub", "mode"), [
    (4, 4, Mode.AUTO),  # MAVSDK mission_raw.start_mission / FlightMode::Mission
    (4, 3, Mode.HOLD),  # FlightMode::Hold = AUTO / LOITER
    (1, 0, Mode.MANUAL),  # FlightMode::Manual (also ArduRover ACRO, which we lack)
    (4, 5, None),  # AUTO / RTL
    (6, 0, None),  # OFFBOARD
    (3, 0, None),  # POSCTL, ArduRover STEERING
])
def test_px4_encoding_of_do_set_mode(main: int, sub: int, mode: Mode | None) -> None:
    """MAVSDK's make_command_px4_mode: p1 = CUSTOM_MODE_ENABLED (| ARMED), p2 main, p3 sub."""
    assert mode_from_command(CUSTOM | ARMED, main, sub) is mode


@pytest.mark.parametrize("params", [
    (0.0, 4.0, 0.0),  # no CUSTOM_MODE_ENABLED: a standard MAV_MODE we do not implement
    (CUSTOM, 11.0, 0.0),  # ArduRover RTL
    (CUSTOM, 4.5, 0.0),
    (CUSTOM, math.inf, 0.0),
    (math.nan, 4.0, 0.0),
])
def test_do_set_mode_naming_no_mode_of_ours(params: tuple[float, float, float]) -> None:
    assert mode_from_command(*params) is None


@pytest.mark.parametrize(("base", "custom", "mode"), [
    (CUSTOM, 10, Mode.AUTO),
    (CUSTOM | ARMED, 15, Mode.GUIDED),
    (CUSTOM, (4 << 16) | (4 << 24), Mode.AUTO),  # PX4 px4_custom_mode: main byte 2, sub byte 3
    (CUSTOM, (4 << 16) | (3 << 24), Mode.HOLD),
    (CUSTOM, 1 << 16, Mode.MANUAL),
    (CUSTOM, (4 << 16) | (4 << 24) | 7, None),  # reserved low bytes set
    (0, 10, None),
    (CUSTOM, 11, None),
])
def test_set_mode_message_in_both_encodings(base: int, custom: int, mode: Mode | None) -> None:
    ground, vehicle = make_codec(255, 190), make_codec(1, 1)
    (msg,) = vehicle.parse(ground.pack(mavlink.MAVLink_set_mode_message(1, base, custom)))
    assert mode_from_set_mode(msg.base_mode, msg.custom_mode) is mode


def test_heartbeat_reads_as_our_modes_in_pymavlink() -> None:
    """pymavlink/MAVProxy decode custom_mode with the ArduRover table for a ground rover."""
    from pymavlink import mavutil

    vehicle, ground = make_codec(1, 1), make_codec(255, 190)
    for mode in Mode:
        (hb,) = ground.parse(vehicle.pack(
            heartbeat_message(mode, armed=True, system_status=mavlink.MAV_STATE_ACTIVE)))
        assert mavutil.mode_string_v10(hb) == mode.name
        assert (hb.type, hb.autopilot, hb.custom_mode, hb.system_status) == (
            mavlink.MAV_TYPE_GROUND_ROVER, mavlink.MAV_AUTOPILOT_GENERIC, int(mode),
            mavlink.MAV_STATE_ACTIVE)
        assert (hb.get_srcSystem(), hb.get_srcComponent()) == (1, 1)


def test_base_mode_flags() -> None:
    assert base_mode_flags(Mode.HOLD, armed=False) == CUSTOM
    assert base_mode_flags(Mode.MANUAL, armed=True) == CUSTOM | ARMED
    assert base_mode_flags(Mode.AUTO, armed=True) == (
        CUSTOM | ARMED | mavlink.MAV_MODE_FLAG_AUTO_ENABLED)
    assert base_mode_flags(Mode.GUIDED, armed=False) == (
        CUSTOM | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED)
