"""``vmnav ground ...``: the ground station at the command line (``ground.station``).

Every subcommand connects (``--connect ADDRESS``: ``udpin:``, ``udpout:``, ``tcp:``,
``tcpin:``, ``serial:`` or ``pty:``, ``shared.link_address``), waits up to
``--timeout`` for the vehicle (``--system`` picks one by system id; default the first
heard), does its one thing and exits: 0 on success, 1 with one line on stderr when the
vehicle is not there, refuses, or (``goto --wait``) does not reach the goal. With
``--log DIR`` every MAVLink packet in and out also goes to ``DIR/ground-NNNN.mcap`` and
``DIR/ground-<stamp>.tlog`` (``ground.ground_log``), configured by the ``[log]`` table of
``--config FILE`` (retention limits, flushing, rotation; ``shared.config.LogConfig``).

Without ``--key`` the link stays on this machine or a wire (``shared.link_security``):
the default is ``udpin:127.0.0.1:14550`` (``udpin:0.0.0.0:14550`` with a key), a
telemetry radio (``serial:``) is fine, and a link open to the network is refused unless
``--insecure`` (a warning on stderr). A stream that ends (the robot's TCP connection, an
unplugged radio) ends the command with one line.

The subcommands with actions of their own are modules registered here: ``goto``,
``memory``, ``teach``, ``params``, ``stop`` (with ``arm``), ``web`` (no wait for a
vehicle), ``keygen`` (connects to nothing), each ``tools.ground_<name>_cmd``. Every other
action is ``(station, args) -> exit code``, called by :func:`run` once the vehicle is heard;
one that takes input of its own (a photo, a name) checks it in ``args.check(args)`` before
anything connects.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from tools import (
    ground_goto_cmd,
    ground_keygen_cmd,
    ground_memory_cmd,
    ground_params_cmd,
    ground_stop_cmd,
    ground_teach_cmd,
    ground_web_cmd,
)
from tools.harness.arg_types import POSITIVE, SYSTEM_ID

if TYPE_CHECKING:
    from ground.station import GroundStation

#: Default wait for the vehicle's HEARTBEAT, s.
DEFAULT_TIMEOUT_S = 5.0
#: ``watch`` without ``--duration`` runs until Ctrl-C: about 31 years, ns.
FOREVER_NS = 10**18

Subparsers = argparse._SubParsersAction  # type: ignore[type-arg]


def add_parser(subparsers: Subparsers) -> None:
    """Register ``vmnav ground`` and its subcommands."""
    ground = subparsers.add_parser(
        "ground", help="the MAVLink ground station: status, goals, teaching",
        description="Talk to a vmnav robot (or several, by system id) over MAVLink.")
    ground.add_argument("--connect", metavar="ADDRESS",
                        help="udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, "
                             "tcpin:HOST:PORT, serial:DEVICE[:BAUD] (default 57600) or "
                             "pty:PATH (default udpin:0.0.0.0:14550 with --key, else "
                             "udpin:127.0.0.1:14550)")
    ground.add_argument("--system", type=SYSTEM_ID, metavar="N",
                        help="the vehicle's system id (default: the first one heard)")
    ground.add_argument("--key", type=Path, metavar="FILE",
                        help="MAVLink 2 signing key file (32 raw bytes, 64 hex digits "
                             "or a passphrase; `vmnav ground keygen FILE` makes one)")
    ground.add_argument("--insecure", action="store_true",
                        help="allow an unsigned --connect link open to the network")
    ground.add_argument("--timeout", type=POSITIVE, default=DEFAULT_TIMEOUT_S, metavar="S",
                        help=f"wait this long for the vehicle, s (default {DEFAULT_TIMEOUT_S:g})")
    ground.add_argument("--log", type=Path, metavar="DIR",
                        help="log every MAVLink packet in and out to DIR/ground-NNNN.mcap "
                             "and DIR/ground-<stamp>.tlog (default: no log)")
    ground.add_argument("--config", type=Path, metavar="FILE",
                        help="a vmnav config file; its [log] table configures --log "
                             "(retention limits, flushing, rotation)")
    sub = ground.add_subparsers(dest="ground_command", metavar="SUBCOMMAND", required=True)

    sub.add_parser("status", help="vehicles seen, mode, battery, mission state"
                   ).set_defaults(action=run_status)
    watch = sub.add_parser("watch", help="live telemetry lines until Ctrl-C")
    watch.add_argument("--duration", type=POSITIVE, metavar="S", help="stop after S seconds")
    watch.set_defaults(action=run_watch)
    ground_memory_cmd.add_parser(sub)
    ground_goto_cmd.add_parser(sub)
    ground_teach_cmd.add_parser(sub)
    ground_params_cmd.add_parser(sub)
    ground_keygen_cmd.add_parser(sub)
    sub.add_parser("drive", help="keyboard teleoperation in MANUAL: w/s speed, a/d turn, "
                   "space stop, q quit").set_defaults(action=run_drive)
    ground_stop_cmd.add_parser(sub)
    ground_web_cmd.add_parser(sub)
    ground.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect, wait for the vehicle, and run the subcommand's action on the station."""
    import time

    from ground.ground_log import GroundLog
    from ground.station import GroundStation
    from shared.clock import WallClock
    from shared.config import load_log_config
    from shared.errors import InputError
    from shared.key_file import read_key_file
    from shared.link_security import check_link

    if args.action is run_drive and not sys.stdin.isatty():
        raise InputError("stdin", "not a terminal: drive reads keys, run it from one")
    if getattr(args, "check", None) is not None:  # the subcommand's own input, before the link
        args.check(args)
    clock = WallClock()
    key = read_key_file(args.key) if args.key is not None else None
    log_config = load_log_config(args.config)  # before connecting: a bad file is one line
    url, line, _ = check_link(args.connect, "--connect", key is not None, args.insecure)
    if line is not None:
        print(f"vmnav ground: {line}", file=sys.stderr)
    unix_offset_ns = time.time_ns() - clock.now_ns()
    with contextlib.ExitStack() as stack:
        station = stack.enter_context(GroundStation.open(
            url, clock, system_id=args.system, key=key, unix_offset_ns=unix_offset_ns))
        if args.log is not None:
            ground_log = GroundLog(dataclasses.replace(log_config, output_dir=str(args.log)),
                                   clock, unix_offset_ns)
            stack.callback(lambda: print(
                f"vmnav ground: {ground_log.summary_text(ground_log.close())}", file=sys.stderr))
            station.packet_taps.append(ground_log.record)
        if getattr(args, "waits_for_vehicle", True):  # ``web`` shows vehicles as they come
            station.wait_vehicle(args.timeout)
        return int(args.action(station, args))


def run_status(station: GroundStation, args: argparse.Namespace) -> int:
    """Print one line per vehicle seen, after asking the one talked to for fresh status."""
    from ground.telemetry_text import status_line
    from shared.mavlink.dialect import mavlink

    for msg_id in (mavlink.MAVLINK_MSG_ID_SYS_STATUS, mavlink.MAVLINK_MSG_ID_MISSION_CURRENT):
        station.request_message(msg_id)
    now_ns = station.clock.now_ns()
    for vehicle in sorted(station.fleet.vehicles.values(), key=lambda v: v.system_id):
        print(status_line(vehicle, now_ns))
    return 0


def run_watch(station: GroundStation, args: argparse.Namespace) -> int:
    """Print a line per telemetry message and per notice until Ctrl-C or ``--duration``."""
    from ground.watch import watch
    from shared.clock import NS_PER_S

    duration_ns = (round(args.duration * NS_PER_S) if args.duration is not None
                   else FOREVER_NS)
    with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C is the normal way out
        watch(station, lambda line: print(line, flush=True), duration_ns)
    return 0


def run_drive(station: GroundStation, args: argparse.Namespace) -> int:
    """Keyboard teleoperation in MANUAL from the terminal (``ground.teleop``)."""
    from ground.teleop import drive_in_terminal
    from shared.mavlink.modes import Mode

    station.set_mode(Mode.MANUAL)
    drive_in_terminal(station, sys.stdin, sys.stdout)
    return 0
