"""``vmnav robot``: the robot process on real transports.

It wires the parts the field runs, each on its own thread, around one loop:

the Pioneer (:class:`robot.pioneer.driver.PioneerDriver` on ``--aria ADDRESS``), the
camera (:class:`robot.camera.VideoCaptureSource` on ``--camera SOURCE``), the ground link
(``robot.vehicle.vehicle_link`` on ``--mavlink ADDRESS``, signed with ``--key FILE``; on
this machine only without a key: ``shared.link_security``; addresses: docs/links.md),
the application (:class:`robot.runtime.RobotRuntime` over ``--memory DIR``), ``--video``'s
live view and ``--foxglove``'s live topics for Foxglove (:mod:`tools.harness.robot_views`).

:class:`robot.process.RobotProcess` assembles them and runs the loop: it hands each
frame to the runtime and, when no frame comes within ``TeleopConfig.frame_timeout_ns``,
tells it the camera stalled (the base stops). Start-up checks come first: every address,
the ground link's transport (a port in use, a missing radio) and the Pioneer's (a missing
device, a refused or unanswered connect: one line in under 2 s), before the Pioneer's
motors are enabled. Parameters set from the ground and goal
photos live in ``--state DIR``. Ctrl-C and SIGTERM end the loop before its next frame
(``tools.harness.stop_signals``; a second one interrupts at once), which stops the base,
sends the Pioneer its CLOSE, and closes the link and the camera; the field log records
all that (ending with how the Pioneer link ended) and is finished last. Exit status: 0,
or 130 after Ctrl-C, 143 after SIGTERM.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
from pathlib import Path

from shared.errors import InputError, TransportError
from tools.harness.arg_types import POSITIVE, SYSTEM_ID
from tools.harness.robot_views import DEFAULT_VIDEO_PORT, FOXGLOVE_PORT, check_views, open_views
from tools.harness.stop_signals import stopped_by_signals


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav robot``."""
    parser = sub.add_parser(
        "robot",
        help="the robot process: Pioneer, camera, MAVLink vehicle",
        description="The robot process: drive a Pioneer through ARIA, read the fisheye "
        "camera, and be a MAVLink vehicle that teaches routes by teleoperation and follows "
        "them to goals sent by a ground station (vmnav ground, MAVProxy, QGroundControl).",
    )
    parser.add_argument("--aria", metavar="ADDRESS",
                        help="the Pioneer: serial:DEVICE[:BAUD], pty:PATH or tcp:HOST:PORT "
                             "(a device path or socket://HOST:PORT also work) [default: the "
                             "config's pioneer.url]")
    parser.add_argument("--camera", metavar="SOURCE",
                        help="cv2.VideoCapture source: device index, file or URL "
                             "(http://127.0.0.1:8080/stream.mjpg) [default: the config's "
                             "camera.source]")
    parser.add_argument("--mavlink", metavar="ADDRESS",
                        help="ground link: udpin:HOST:PORT, udpout:HOST:PORT, tcpin:HOST:PORT, "
                             "tcp:HOST:PORT, serial:DEVICE[:BAUD] (default 57600) or pty:PATH "
                             "[default: udpin:0.0.0.0:14550 with --key, else "
                             "udpin:127.0.0.1:14550, this machine only]")
    parser.add_argument("--memory", required=True, type=Path, metavar="DIR",
                        help="the visual memory (created when teaching into an empty folder)")
    parser.add_argument("--calibration", type=Path, metavar="FILE",
                        help="camera calibration JSON for a new memory [default: the "
                             "simulator's 800x600 camera]; a stored memory has its own")
    parser.add_argument("--state", type=Path, default=Path("vmnav-state"), metavar="DIR",
                        help="parameters set from the ground, uploaded goal photos and the "
                             "signing timestamps [default: %(default)s]")
    parser.add_argument("--config", metavar="FILE", help="vmnav TOML config file")
    parser.add_argument("--system", type=SYSTEM_ID, metavar="N",
                        help="MAVLink system id [default: the config's mavlink.system_id]")
    parser.add_argument("--key", type=Path, metavar="FILE",
                        help="MAVLink 2 signing key file (vmnav ground keygen FILE makes one): "
                             "sign everything, drop unsigned input")
    parser.add_argument("--insecure", action="store_true",
                        help="allow an unsigned --mavlink link open to the network (anyone "
                             "on it can drive the robot; warns at start and to each ground "
                             "station), and --foxglove on a host off this machine")
    parser.add_argument("--log", type=Path, metavar="DIR",
                        help="write the field log to DIR/robot-NNNN.mcap: frames, matches, "
                             "servo state, commands, odometry, SIPs, MAVLink in and out, events "
                             "[default: the config's log.output_dir]")
    parser.add_argument("--no-log", action="store_true", help="write no field log")
    parser.add_argument("--video", metavar="SPEC",
                        help="serve what the camera sees as MJPEG over HTTP (/stream.mjpg, "
                             "/snapshot.jpg; ?matches=1 draws the matched points), advertised "
                             "to ground stations by the MAVLink camera protocol: http:PORT or "
                             f"http:HOST:PORT (host 127.0.0.1 unless given; port "
                             f"{DEFAULT_VIDEO_PORT} for plain http; 0 picks a free one) "
                             "[default: off]")
    parser.add_argument("--foxglove", metavar="[HOST:]PORT",
                        help="serve the live topics (camera, servo state, tf, commands: the "
                             "field log's topics and schemas) over the Foxglove WebSocket "
                             "protocol, for Foxglove or Lichtblick (docs/foxglove.md); host "
                             "127.0.0.1 unless given, another needs --insecure; port "
                             f"{FOXGLOVE_PORT} is the viewers' default, 0 picks a free one "
                             "[default: the config's foxglove.address, off]")
    parser.add_argument("--duration", type=POSITIVE, metavar="S",
                        help="stop after this long, s [default: until Ctrl-C or SIGTERM]")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Open every part (a clear error for the first that fails), run the robot process."""
    import numpy as np

    from robot.camera import VideoCaptureSource
    from robot.config import load_config
    from robot.field_log import FieldLog
    from robot.pioneer.connection import CONNECT_TIMEOUT_S, why_not_connected
    from robot.pioneer.driver import PioneerDriver
    from robot.pioneer.serial_link import aria_address
    from robot.process import RobotParts, RobotProcess
    from robot.vehicle.options import SigningSetup, VehicleFiles
    from robot.vehicle.vehicle_link import open_vehicle_transport, transport_address
    from shared.calibration import read_camera
    from shared.clock import WallClock, unix_offset_ns
    from shared.key_file import read_key_file
    from shared.link_security import INSECURE_NOTICE, check_link
    from shared.memory import open_or_create

    config = load_config(args.config)
    config = dataclasses.replace(
        config,
        pioneer=dataclasses.replace(config.pioneer, **({} if args.aria is None
                                                       else {"url": args.aria})),
        camera=dataclasses.replace(config.camera, **({} if args.camera is None
                                                     else {"source": args.camera})),
        mavlink=dataclasses.replace(config.mavlink, **({} if args.system is None
                                                       else {"system_id": args.system})))
    if args.duration is not None and not args.duration > 0:
        raise InputError("--duration", f"must be > 0 seconds, got {args.duration}")
    views = check_views(args.video, args.foxglove, config.foxglove.address, args.insecure)
    aria_option = "--aria" if args.aria is not None else "[pioneer] url"
    aria_address(config.pioneer.url, aria_option)
    key = read_key_file(args.key) if args.key is not None else None
    link_check = check_link(args.mavlink, "--mavlink", key is not None, args.insecure)
    url = link_check.url
    memory = open_or_create(args.memory, None if args.calibration is None
                            else read_camera(args.calibration))
    signing = None
    clock = WallClock()
    unix_offset = unix_offset_ns(clock)  # for signing and the log's Unix times
    if key is not None:
        signing = SigningSetup(key, unix_offset,
                               timestamp_file=args.state / "signing-timestamps.json")
    # The process closes what `owned` holds after the runtime stopped the base, then has
    # the field log record how the Pioneer link ended, and finishes the log last
    # (robot.process, rule 4).
    with contextlib.ExitStack() as owned:
        transport = open_vehicle_transport(url)
        owned.callback(transport.close)  # until the process owns it
        camera = owned.enter_context(VideoCaptureSource(config.camera, clock, memory.camera))
        view, bridge = open_views(views, config, unix_offset, owned)
        driver = owned.enter_context(PioneerDriver.from_config(config.pioneer, clock))
        try:
            driver.open_transport()
        except TransportError as e:
            raise TransportError(f"{aria_option} {config.pioneer.url}", e.problem) from None
        driver.start_thread()
        if not driver.wait_connected(round(CONNECT_TIMEOUT_S * 1e9)):
            raise TransportError(config.pioneer.url, why_not_connected(driver))
        log = None
        if not args.no_log:  # once camera and robot answered
            log_config = (config.log if args.log is None
                          else dataclasses.replace(config.log, output_dir=str(args.log)))
            log = FieldLog(log_config, "robot", config.camera.mount,
                           {"source": "vmnav robot", "aria": config.pioneer.url,
                            "camera": config.camera.source}, unix_offset_ns=unix_offset)
            driver.sip_observers.append(log.sip)

        def pioneer_closed(log: FieldLog) -> None:
            log.pioneer_closed(clock.now_ns(), driver.status(), driver.counters())

        files = VehicleFiles(args.memory, args.state / "upload", args.state / "params.parm")
        parts = RobotParts(memory, driver, camera, clock, config, files, np.random.default_rng(),
                           log=log, signing=signing,
                           link_warning=INSECURE_NOTICE if link_check.insecure else None,
                           video=view, foxglove=bridge)
        with RobotProcess(parts, transport, owned=owned.pop_all(),
                          log_end=pioneer_closed) as process:
            identity = driver.status().identity
            width, height = camera.size_wh
            print(f"vmnav robot: {identity.name if identity else 'Pioneer'!r} on "
                  f"{config.pioneer.url}; camera {config.camera.source} ({width}x{height}); "
                  f"MAVLink system {config.mavlink.system_id} on {transport_address(transport)}"
                  f"{' (signed)' if signing else ''}; memory {args.memory}: "
                  f"{len(memory.paths)} paths, {len(memory.keyframes)} key images", flush=True)
            if view is not None:
                print(f"vmnav robot: live view on {view.server.stream_url}", flush=True)
            if bridge is not None:
                print(f"vmnav robot: live topics for Foxglove on {bridge.url}", flush=True)
            for line in (link_check.line, views.line):
                if line is not None:
                    print(f"vmnav robot: {line}", flush=True)
            with stopped_by_signals(process.stop) as signalled:
                ended = process.run(end_ns=None if args.duration is None
                                    else clock.now_ns() + round(args.duration * 1e9))
    if signalled.signum is not None:
        ended = f"stopped by {signalled.name}"
    print(f"vmnav robot: {ended}; base stopped, links closed", flush=True)
    return signalled.exit_status

