"""``vmnav ground stop`` and ``vmnav ground arm``: the emergency stop and its end.

``stop`` force-disarms the robot (COMPONENT_ARM_DISARM with param2 21196, the emergency
stop of QGroundControl, ArduRover and MAVProxy's ``disarm force``): the robot stops on
receipt with the Pioneer's E_STOP, ends its mission (``e_stop``) and holds, disarmed
(docs/safety.md). ``arm`` arms it again and waits for the HEARTBEAT that says so.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ground.station import GroundStation


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground stop`` and ``vmnav ground arm``."""
    ground_sub.add_parser(
        "stop", help="emergency stop: the robot stops at once and holds until re-armed",
        description="Force-disarm the robot (COMPONENT_ARM_DISARM with param2 21196, "
        "QGroundControl's emergency stop): it stops on receipt with the Pioneer's E_STOP, "
        "ends any mission and holds until `vmnav ground arm`.").set_defaults(action=run_stop)
    ground_sub.add_parser("arm", help="arm the robot (ends an emergency stop's hold)"
                          ).set_defaults(action=run_arm)


def run_stop(station: GroundStation, args: argparse.Namespace) -> int:
    """The emergency stop, acknowledged."""
    started_ns = station.clock.now_ns()
    station.emergency_stop()
    took_ms = (station.clock.now_ns() - started_ns) / 1e6
    print(f"vehicle {station.vehicle.system_id}: emergency stop accepted in {took_ms:.0f} ms; "
          "holding until `vmnav ground arm`")
    return 0


def run_arm(station: GroundStation, args: argparse.Namespace) -> int:
    """Arm the robot; returns once its HEARTBEAT says armed."""
    station.arm()
    print(f"vehicle {station.vehicle.system_id}: armed")
    return 0
