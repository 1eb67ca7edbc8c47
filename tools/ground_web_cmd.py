"""``vmnav ground web``: the ground station as a web app (``ground.web``), on
http://127.0.0.1:8080 by default.

Registered under ``vmnav ground`` by :mod:`tools.ground_cmd`, which connects (``--connect``,
``--key``, ``--log``) and, for this subcommand only, does not wait for a vehicle: the page
shows the vehicles as they are heard.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
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
        "a gamepad, the ground logs. Serving an address other than loopback takes an access "
        "token, generated and printed at start or read from --token-file.")
    web.add_argument("--http", type=http_address, default=http_address(DEFAULT_HTTP),
                     metavar="HOST:PORT",
                     help=f"where to serve the page (default {DEFAULT_HTTP}; port 0 picks one; "
                          "an address other than loopback, e.g. 0.0.0.0:8080, requires a token)")
    web.add_argument("--token-file", type=Path, metavar="FILE",
                     help="the access token every request must carry, on FILE's first line "
                          "(at least 16 of A-Z a-z 0-9 . _ ~ -); without it, one is generated "
                          "when --http is not loopback")
    web.set_defaults(action=run_web, waits_for_vehicle=False, check=check_web)


def check_web(args: argparse.Namespace) -> None:
    """Read the token file before connecting: a bad one is one line, and nothing opened."""
    from ground.web.access import read_token_file

    if args.token_file is not None:
        read_token_file(args.token_file)


def web_config(args: argparse.Namespace) -> WebConfig:
    """The server's config from the arguments (the token read or generated here)."""
    from ground.web.access import generate_token, read_token_file
    from ground.web.server import WebConfig
    from shared.guarded_http import is_loopback_name

    host, port = args.http
    token = None
    if args.token_file is not None:
        token = read_token_file(args.token_file)
    elif not is_loopback_name(host):
        token = generate_token()
    return WebConfig(host=host, port=port, vehicle_timeout_s=args.timeout, token=token,
                     log_dir=args.log)


def run_web(station: GroundStation, args: argparse.Namespace) -> int:
    """Serve until Ctrl-C or SIGTERM."""
    from ground.web.server import serve

    serve(station, station.clock, web_config(args),
          lambda line: print(f"vmnav ground web: {line}", file=sys.stderr, flush=True))
    return 0
