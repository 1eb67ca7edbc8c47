"""``vmnav sim serve``: the emulated Pioneer 3-AT on a pty and/or TCP, in real time.

Registered under ``vmnav sim`` by :mod:`tools.sim_cmd`. The simulation steps to the
wall clock and the ARIA server answers one client at a time (``sim.pioneer.server``)
until Ctrl-C, SIGTERM or ``--duration``. With ``--video`` the robot's fisheye camera
is an MJPEG stream over HTTP (``sim.camera_server``), rendered from the same
simulation every frame period.
"""

from __future__ import annotations

import argparse
import math
from contextlib import ExitStack, closing
from dataclasses import dataclass
from pathlib import Path

from shared.errors import InputError
from tools.harness.sim_args import (
    add_sim_arguments,
    add_start_arguments,
    place_at_start,
    sim_config_from_args,
)
from tools.harness.stop_signals import stopped_by_signals
from tools.harness.tcp_spec import TcpSpec, parse_http_spec, tcp_spec

DEFAULT_ARIA = "tcp:8101"
DEFAULT_VIDEO_PORT = 8080
DEFAULT_CONTROL_PORT = 8081


@dataclass(frozen=True, slots=True)
class PtySpec:
    """Serve on a new pseudo-terminal, optionally symlinked."""

    symlink: Path | None = None


def parse_aria_spec(text: str) -> PtySpec | TcpSpec:
    """An ``--aria`` value: ``pty``, ``pty:LINK``, ``tcp``, ``tcp:PORT`` or ``tcp:HOST:PORT``.

    Raises:
        InputError: anything else (the message names ``--aria`` and the value).
    """
    kind, _, rest = text.partition(":")
    if kind == "pty":
        return PtySpec(Path(rest) if rest else None)
    if kind == "tcp":
        return tcp_spec("--aria", text, rest, int(DEFAULT_ARIA.split(":")[1]))
    raise InputError(
        "--aria", f"{text!r} is not pty, pty:LINK, tcp:PORT or tcp:HOST:PORT"
    )


def parse_video_spec(text: str, option: str = "--video",
                     default_port: int = DEFAULT_VIDEO_PORT) -> TcpSpec:
    """A ``--video`` (or ``--control``) value: ``http``, ``http:PORT`` or ``http:HOST:PORT``.

    Raises:
        InputError: anything else (the message names ``option`` and the value).
    """
    return parse_http_spec(text, option, default_port)


def add_parser(sim_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav sim serve``."""
    serve = sim_sub.add_parser(
        "serve",
        help="serve an emulated Pioneer 3-AT (ARIA server) on a pty and/or TCP, in real time",
        description="Run a simulated world in real time with its robot as an emulated "
        "Pioneer 3-AT-SH that ARIA clients (stock ARIA, vmnav's driver) connect to over a "
        "serial pty or TCP (one client at a time), and with --video its fisheye camera as an "
        "MJPEG stream over HTTP that cv2.VideoCapture reads like a network camera. Stop with "
        "Ctrl-C.",
    )
    add_sim_arguments(serve)
    serve.add_argument(
        "--aria",
        action="append",
        metavar="SPEC",
        help="where to serve ARIA, repeatable: pty, pty:LINK (also symlink LINK to the pty), "
        f"tcp:PORT, tcp:HOST:PORT (default host 127.0.0.1) [default: {DEFAULT_ARIA}]",
    )
    serve.add_argument(
        "--video",
        metavar="SPEC",
        help="also serve the robot's camera as MJPEG over HTTP (for cv2.VideoCapture, "
        "ffplay, a browser): http, http:PORT, http:HOST:PORT (default host 127.0.0.1, "
        f"port {DEFAULT_VIDEO_PORT}; port 0 picks a free one) [default: no camera]",
    )
    serve.add_argument(
        "--control",
        metavar="SPEC",
        help="also serve the simulator's truth, robot placement and boxes over HTTP (GET "
        "/truth, POST /place, GET/POST /obstacles, DELETE /obstacles/<id>; for vmnav demo "
        "--hil and safety scenarios): http, http:PORT, http:HOST:PORT (port "
        f"{DEFAULT_CONTROL_PORT} unless given) [default: none]",
    )
    serve.add_argument(
        "--jpeg-quality", type=int, metavar="Q",
        help="JPEG quality of the --video frames, 1-100 [default: [sim.sensor] jpeg_quality, "
        "80]",
    )
    serve.add_argument(
        "--duration", type=float, metavar="S", help="stop after S seconds [default: never]"
    )
    add_start_arguments(serve)
    serve.set_defaults(run=run_serve)


def run_serve(args: argparse.Namespace) -> int:
    """Open the transports, print where they are, serve until stopped, print the counts."""
    specs = [parse_aria_spec(text) for text in args.aria or [DEFAULT_ARIA]]
    video = None if args.video is None else parse_video_spec(args.video)
    control = (None if args.control is None
               else parse_video_spec(args.control, "--control", DEFAULT_CONTROL_PORT))
    if args.jpeg_quality is not None and not 1 <= args.jpeg_quality <= 100:
        raise InputError("--jpeg-quality", f"must be 1-100, got {args.jpeg_quality}")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise InputError("--duration", f"must be > 0 seconds, got {args.duration}")
    config, camera = sim_config_from_args(args)

    from shared.clock import WallClock
    from sim.camera_server import CameraServer
    from sim.control_server import ControlHook, ControlServer
    from sim.pioneer import PtyLink, TcpListener
    from sim.pioneer.world_server import pioneer_server

    with ExitStack() as opened:  # closes everything, also if a step fails
        links, listeners = [], []
        for spec in specs:  # first: a port in use fails before the world is built
            if isinstance(spec, PtySpec):
                links.append(opened.enter_context(closing(PtyLink(spec.symlink))))
            else:
                listener = TcpListener(spec.host, spec.port)
                listeners.append(opened.enter_context(closing(listener)))
        video_server = None if video is None else opened.enter_context(
            CameraServer(video.host, video.port, args.jpeg_quality or config.sensor.jpeg_quality))
        server = opened.enter_context(
            pioneer_server(config, camera, links, listeners, video_server))
        emulator = server.emulator
        sim = emulator.simulation
        place_at_start(args, sim)
        control_server = None
        if control is not None:
            hook = ControlHook(sim)
            sim.add_step_hook(hook)
            control_server = opened.enter_context(ControlServer(hook, control.host, control.port))
        at = sim.body.pose_w
        print(f"vmnav sim serve: world {config.world} (seed {config.seed}), robot "
              f"'{emulator.identity.name}' ({emulator.identity.subclass}) at x {at.x_m:.2f} m, "
              f"y {at.y_m:.2f} m, yaw {math.degrees(at.yaw_rad):.1f} deg")
        for link in links:
            also = f" (also {link.symlink})" if link.symlink else ""
            print(f"  ARIA on pty {link.path}{also}")
        for listener in listeners:
            print(f"  ARIA on tcp {listener.host}:{listener.port}")
        if video_server is not None:
            print(f"  camera on {video_server.stream_url} "
                  f"(one frame: {video_server.snapshot_url})")
        if control_server is not None:
            print(f"  control on {control_server.url} (GET /truth, POST /place, "
                  "GET/POST /obstacles, DELETE /obstacles/<id>)")
        print("  Ctrl-C stops", flush=True)
        duration_ns = None if args.duration is None else round(args.duration * 1e9)
        with stopped_by_signals(server.stop):
            server.run(WallClock(), duration_ns)
    s = emulator.stats
    print(f"stopped after {sim.now_ns / 1e9:.1f} s of simulation: {s.sessions} session(s), "
          f"{s.sips_sent} SIPs, {s.commands} commands, {s.unknown_commands} unknown, "
          f"{s.refused_commands} refused, {s.bad_checksums} bad checksums, "
          f"{s.handler_errors} handler errors, {server.refused_clients} client(s) refused")
    if video_server is not None:
        v = video_server.stats()
        print(f"camera: {v.published} frames, {v.clients} stream client(s)")
    return 0
