"""``vmnav ground web``: the ground station as a web app (``ground.web``), on
http://127.0.0.1:8080 by default.

Registered under ``vmnav ground`` by :mod:`tools.ground_cmd`, which connects (``--connect``,
``--key``, ``--log``) and, for this subcommand only, does not wait for a vehicle: the page
shows the vehicles as they are heard.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ground.station import GroundStation
    from ground.web.server import WebConfig

DEFAULT_HTTP = "127.0.0.1:8080"


def http_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:PORT`` for IPv6) as (host, port); argparse's usage error if not."""
    host, sep, port = text.rpartition(":")
    host = host.removeprefix("[").removesuffix("]")
    if not sep or not host or not port.isdigit() or int(port) > 65535:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, e.g. {DEFAULT_HTTP}, got {text!r}")
    return host, int(port)


def add_parser(ground_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav ground web [--http HOST:PORT]``."""
    web = ground_sub.add_parser(
        "web", help="the ground station as a web app: fleet, live servo state, memory, teach",
        description="Serve the ground station's web app until Ctrl-C: every vehicle heard, "
        "the live servo state and odometry of one, its memory's key images (click one to go "
        "there), mode/arm/hold/emergency stop, parameters, and teaching with the keyboard or "
        "a gamepad. Loopback only.")
    web.add_argument("--http", type=http_address, default=http_address(DEFAULT_HTTP),
                     metavar="HOST:PORT",
                     help=f"where to serve the page (default {DEFAULT_HTTP}; port 0 picks one)")
    web.set_defaults(action=run_web, waits_for_vehicle=False)


def web_config(args: argparse.Namespace) -> WebConfig:
    """The server's config from the arguments."""
    from ground.web.server import WebConfig

    host, port = args.http
    return WebConfig(host=host, port=port, vehicle_timeout_s=args.timeout)


def run_web(station: GroundStation, args: argparse.Namespace) -> int:
    """Serve until Ctrl-C or SIGTERM."""
    from ground.web.server import serve

    serve(station, station.clock, web_config(args),
          lambda line: print(f"vmnav ground web: {line}", file=sys.stderr, flush=True))
    return 0
