"""``vmnav ground ...``: the ground station at the command line (``ground.station``).

Every subcommand connects (``--connect``, pymavlink connection strings), waits up to
``--timeout`` for the vehicle (``--system`` picks one by system id; default the first
heard), does its one thing and exits: 0 on success, 1 with one line on stderr when the
vehicle is not there, refuses, or (``goto --wait``) does not reach the goal. With
``--log DIR`` every MAVLink packet in and out also goes to ``DIR/ground-NNNN.mcap`` and
``DIR/ground-<stamp>.tlog`` (``ground.ground_log``).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ground.fleet import VehicleState
    from ground.station import GroundStation, PacketTap
    from shared.clock import Clock

#: Default wait for the vehicle's HEARTBEAT, s.
DEFAULT_TIMEOUT_S = 5.0
#: Default wait for a goal to be reached (``goto --wait``), s.
DEFAULT_WAIT_S = 600.0
#: Where the robot serves its key image thumbnails (``robot.vehicle.ftp_memory``).
THUMBNAILS = "/memory/thumbnails"
#: ``watch`` without ``--duration`` runs until Ctrl-C: about 31 years, ns.
FOREVER_NS = 10**18

Subparsers = argparse._SubParsersAction  # type: ignore[type-arg]


def add_parser(subparsers: Subparsers) -> None:
    """Register ``vmnav ground`` and its subcommands."""
    from ground import DEFAULT_URL

    ground = subparsers.add_parser(
        "ground", help="the MAVLink ground station: status, goals, teaching",
        description="Talk to a vmnav robot (or several, by system id) over MAVLink.")
    ground.add_argument("--connect", default=DEFAULT_URL, metavar="URL",
                        help=f"udpin:HOST:PORT or udpout:HOST:PORT (default {DEFAULT_URL})")
    ground.add_argument("--system", type=int, metavar="N",
                        help="the vehicle's system id (default: the first one heard)")
    ground.add_argument("--key", type=Path, metavar="FILE",
                        help="MAVLink 2 signing key file (32 raw bytes, 64 hex digits "
                             "or a passphrase)")
    ground.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT_S, metavar="S",
                        help=f"wait this long for the vehicle, s (default {DEFAULT_TIMEOUT_S:g})")
    ground.add_argument("--log", type=Path, metavar="DIR",
                        help="log every MAVLink packet in and out to DIR/ground-NNNN.mcap "
                             "and DIR/ground-<stamp>.tlog (default: no log)")
    sub = ground.add_subparsers(dest="ground_command", metavar="SUBCOMMAND", required=True)

    sub.add_parser("status", help="vehicles seen, mode, battery, mission state"
                   ).set_defaults(action=run_status)
    watch = sub.add_parser("watch", help="live telemetry lines until Ctrl-C")
    watch.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    watch.set_defaults(action=run_watch)

    memory = sub.add_parser("memory", help="the robot's visual memory over MAVLink FTP")
    memory_sub = memory.add_subparsers(dest="memory_command", metavar="ACTION", required=True)
    memory_sub.add_parser("list", help="key images with a thumbnail").set_defaults(
        action=run_memory_list)
    get = memory_sub.add_parser("get", help="download key image thumbnails (PNG)")
    get.add_argument("ids", type=int, nargs="+", metavar="ID", help="key image ids")
    get.add_argument("--out", type=Path, required=True, metavar="DIR", help="folder to write to")
    get.set_defaults(action=run_memory_get)

    goto = sub.add_parser("goto", help="drive to a key image, or to where a photo was taken",
                          description="Upload a one-goal mission and start it, or upload a "
                          "photo and ask the robot to localize it and go there.")
    goto.add_argument("goal_key", type=int, nargs="?", metavar="KEY", help="goal key image id")
    goto.add_argument("--image", type=Path, metavar="PHOTO", help="goal photo (JPEG, PNG...)")
    goto.add_argument("--wait", action="store_true",
                      help="wait for the outcome; exit code 0 reached, 1 not")
    goto.add_argument("--wait-timeout", type=float, default=DEFAULT_WAIT_S, metavar="S",
                      help=f"give up waiting after S seconds (default {DEFAULT_WAIT_S:g})")
    goto.set_defaults(action=run_goto)

    teach = sub.add_parser("teach", help="record a visual path while driving")
    teach_sub = teach.add_subparsers(dest="teach_command", metavar="ACTION", required=True)
    start = teach_sub.add_parser("start", help="start recording")
    start.add_argument("name", metavar="NAME", help="the path's name (up to 21 ASCII characters)")
    start.set_defaults(action=run_teach_start)
    teach_sub.add_parser("stop", help="stop; the path joins the memory").set_defaults(
        action=run_teach_stop)

    params = sub.add_parser("params", help="the robot's parameters")
    params_sub = params.add_subparsers(dest="params_command", metavar="ACTION", required=True)
    params_sub.add_parser("list", help="every parameter").set_defaults(action=run_params_list)
    param_get = params_sub.add_parser("get", help="one parameter")
    param_get.add_argument("name", metavar="NAME")
    param_get.set_defaults(action=run_params_get)
    param_set = params_sub.add_parser("set", help="set one parameter (persisted on the robot)")
    param_set.add_argument("name", metavar="NAME")
    param_set.add_argument("value", type=float, metavar="VALUE")
    param_set.set_defaults(action=run_params_set)

    sub.add_parser("drive", help="keyboard teleoperation in MANUAL: w/s speed, a/d turn, "
                   "space stop, q quit").set_defaults(action=run_drive)
    ground.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Connect, wait for the vehicle, and run the subcommand's action on the station."""
    import time

    from ground.station import GroundStation
    from shared.clock import WallClock
    from shared.errors import InputError
    from shared.key_file import read_key_file

    if args.action is run_drive and not sys.stdin.isatty():
        raise InputError("stdin", "not a terminal: drive reads keys, run it from one")
    clock = WallClock()
    key = read_key_file(args.key) if args.key is not None else None
    unix_offset_ns = time.time_ns() - clock.now_ns()
    with contextlib.ExitStack() as stack:
        station = stack.enter_context(GroundStation.open(
            args.connect, clock, system_id=args.system, key=key, unix_offset_ns=unix_offset_ns))
        if args.log is not None:
            station.packet_taps.append(open_ground_log(stack, args.log, clock, unix_offset_ns))
        station.wait_vehicle(args.timeout)
        return int(args.action(station, args))


def open_ground_log(stack: contextlib.ExitStack, folder: Path, clock: Clock,
                    unix_offset_ns: int) -> PacketTap:
    """Open the ground log in ``folder``, closed by ``stack`` with a line on stderr naming
    its files; its packet tap."""
    from ground.ground_log import GroundLog
    from shared.config import LogConfig

    ground_log = GroundLog(LogConfig(output_dir=str(folder)), clock, unix_offset_ns)

    def close() -> None:
        stats = ground_log.close()
        files = ", ".join(str(path) for path in (*stats.files, ground_log.tlog.path))
        print(f"vmnav ground: logged {ground_log.tlog.records} packets to {files}",
              file=sys.stderr)

    stack.callback(close)
    return ground_log.record


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
    from ground.telemetry_text import describe
    from shared.clock import NS_PER_S

    start_ns = station.clock.now_ns()
    shown: dict[int, int] = {}  # system id -> notices printed

    def show(vehicle: VehicleState, msg: Any) -> None:
        elapsed_s = (station.clock.now_ns() - start_ns) / NS_PER_S
        stamp = f"{elapsed_s:8.2f} s  vehicle {vehicle.system_id}"
        for notice in vehicle.notices[shown.get(vehicle.system_id, 0):]:
            print(f"{stamp}  NOTICE: {notice}", flush=True)
        shown[vehicle.system_id] = len(vehicle.notices)
        line = describe(msg)
        if line is not None:
            print(f"{stamp}  {msg.get_type()}: {line}", flush=True)

    station.listeners.append(show)
    duration_ns = (round(args.duration * NS_PER_S) if args.duration is not None
                   else FOREVER_NS)
    with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C is the normal way out
        station.run_until(lambda: False, duration_ns)
    return 0


def run_memory_list(station: GroundStation, args: argparse.Namespace) -> int:
    """Print the key image ids that have a thumbnail, one per line with its size."""
    entries = station.ftp_list(THUMBNAILS)
    ids = sorted(int(e.name.removesuffix(".png")) for e in entries
                 if not e.is_dir and e.name.removesuffix(".png").isdigit())
    sizes = {e.name: e.size for e in entries}
    for key in ids:
        print(f"{key}\t{sizes[f'{key}.png']} bytes")
    print(f"{len(ids)} key images", file=sys.stderr)
    return 0


def run_memory_get(station: GroundStation, args: argparse.Namespace) -> int:
    """Download the thumbnails of ``args.ids`` into ``args.out``."""
    from shared.atomic_file import write_bytes_atomic

    args.out.mkdir(parents=True, exist_ok=True)
    for key in args.ids:
        path = args.out / f"{key}.png"
        write_bytes_atomic(path, station.ftp_get(f"{THUMBNAILS}/{key}.png"))
        print(path)
    return 0


def run_goto(station: GroundStation, args: argparse.Namespace) -> int:
    """Dispatch the goal; with ``--wait``, 0 when reached and 1 when not."""
    from shared.errors import InputError
    from shared.mavlink.mission.goal import Goal

    if (args.goal_key is None) == (args.image is None):
        raise InputError("goto", "give either a key image id KEY or --image PHOTO")
    vehicle = station.vehicle
    if args.image is not None:
        try:
            data = args.image.read_bytes()
        except OSError as e:
            raise InputError(args.image, f"cannot read the goal photo: {e.strerror}") from None
        photo_id = station.goto_photo(data, args.image.suffix)
        print(f"vehicle {vehicle.system_id}: going to photo {args.image.name} "
              f"(uploaded as photo {photo_id})")
    else:
        try:
            goal = Goal(args.goal_key)
        except ValueError as e:
            raise InputError("KEY", str(e)) from None
        station.upload_goals([goal])
        station.start_mission()
        print(f"vehicle {vehicle.system_id}: going to key image {args.goal_key}")
    if not args.wait:
        return 0
    if station.wait_mission_done(args.wait_timeout):
        print(f"vehicle {vehicle.system_id}: goal reached")
        return 0
    last = f" (last notice: {vehicle.notices[-1]})" if vehicle.notices else ""
    why = (f"still on the way after {args.wait_timeout:g} s" if station.mission_outcome is None
           else "the run stopped short")
    print(f"vmnav ground: goal not reached: {why}{last}", file=sys.stderr)
    return 1


def run_teach_start(station: GroundStation, args: argparse.Namespace) -> int:
    """Start recording path ``args.name``."""
    station.teach_start(args.name)
    print(f"vehicle {station.vehicle.system_id}: teaching {args.name!r}")
    return 0


def run_teach_stop(station: GroundStation, args: argparse.Namespace) -> int:
    """Stop recording."""
    station.teach_stop()
    print(f"vehicle {station.vehicle.system_id}: teaching stopped")
    return 0


def run_params_list(station: GroundStation, args: argparse.Namespace) -> int:
    """Print every parameter as ``NAME = value``."""
    for name, value in station.fetch_params().items():
        print(f"{name} = {value:g}")
    return 0


def run_params_get(station: GroundStation, args: argparse.Namespace) -> int:
    """Print one parameter."""
    print(f"{args.name} = {station.get_param(args.name):g}")
    return 0


def run_params_set(station: GroundStation, args: argparse.Namespace) -> int:
    """Set one parameter and print the value in force."""
    print(f"{args.name} = {station.set_param(args.name, args.value):g}")
    return 0


def run_drive(station: GroundStation, args: argparse.Namespace) -> int:
    """Keyboard teleoperation in MANUAL from the terminal (``ground.teleop``)."""
    import select
    import termios
    import tty

    from ground.teleop import KeyboardTeleop, drive
    from shared.mavlink.modes import Mode

    station.set_mode(Mode.MANUAL)
    fd = sys.stdin.fileno()

    def read_keys() -> str:
        keys = ""
        while select.select([fd], [], [], 0)[0]:
            keys += sys.stdin.read(1)
        return keys

    def show(teleop: KeyboardTeleop) -> None:
        print(f"\rforward {teleop.x:+.1f}  yaw {teleop.r:+.1f}   ", end="", flush=True)

    print("w/s speed, a/d turn, space stop, q quit")
    saved = termios.tcgetattr(fd)
    tty.setcbreak(fd)
    try:
        drive(station, read_keys, station.clock, show)
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)
        print()
    return 0
