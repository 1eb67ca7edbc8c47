"""``vmnav ground params list|get|set``: the robot's parameters.

Registered under ``vmnav ground`` by :mod:`tools.ground_cmd`, which connects and
calls the action with the station.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from tools.harness.arg_types import FINITE

if TYPE_CHECKING:
    from ground.station import GroundStation


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground params list``, ``get NAME`` and ``set NAME VALUE``."""
    params = ground_sub.add_parser("params", help="the robot's parameters")
    params_sub = params.add_subparsers(dest="params_command", metavar="ACTION", required=True)
    params_sub.add_parser("list", help="every parameter").set_defaults(action=run_list)
    param_get = params_sub.add_parser("get", help="one parameter")
    param_get.add_argument("name", metavar="NAME")
    param_get.set_defaults(action=run_get)
    param_set = params_sub.add_parser("set", help="set one parameter (persisted on the robot)")
    param_set.add_argument("name", metavar="NAME")
    param_set.add_argument("value", type=FINITE, metavar="VALUE")
    param_set.set_defaults(action=run_set)


def run_list(station: GroundStation, args: argparse.Namespace) -> int:
    """Print every parameter as ``NAME = value``."""
    for name, value in station.fetch_params().items():
        print(f"{name} = {value:g}")
    return 0


def run_get(station: GroundStation, args: argparse.Namespace) -> int:
    """Print one parameter."""
    print(f"{args.name} = {station.get_param(args.name):g}")
    return 0


def run_set(station: GroundStation, args: argparse.Namespace) -> int:
    """Set one parameter and print the value in force."""
    print(f"{args.name} = {station.set_param(args.name, args.value):g}")
    return 0
