"""What ``vmnav robot`` serves for people to watch: the live view (``--video``, MJPEG over
HTTP: :mod:`robot.video`) and the live topics (``--foxglove``, the Foxglove WebSocket
protocol: :mod:`robot.foxglove_bridge`).

Both listen on this machine only (127.0.0.1) unless a host is given. Nobody signs in to
the live topics, so a ``--foxglove`` host off this machine is refused without
``--insecure`` (the rule of an unsigned MAVLink link, ``shared.link_security``): anyone
who reaches it would see the camera and where the robot goes. Both servers are checked
(:func:`check_views`) before anything opens and opened (:func:`open_views`) before the
Pioneer's motors are enabled, so a port in use is one line at start.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

from shared.errors import InputError
from shared.ipv4 import is_loopback, resolve_ipv4
from tools.harness.tcp_spec import TcpSpec, parse_http_spec, tcp_spec

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.foxglove_bridge import FoxgloveBridge
    from robot.video import LiveView

#: The live view's port for a plain ``--video http``.
DEFAULT_VIDEO_PORT = 8090
#: The Foxglove WebSocket protocol's usual port (Foxglove's and Lichtblick's default URL).
FOXGLOVE_PORT = 8765


@dataclass(frozen=True, slots=True)
class Views:
    """What to serve, checked (:func:`check_views`).

    Attributes:
        video: the live view's address; None: not served.
        foxglove: the live topics' address; None: not served.
        foxglove_where: where that address came from, with it, for messages
            (``--foxglove 8765``, ``[foxglove] address 0.0.0.0:8765``).
        line: a warning for the user at start (live topics open to the network), or None.
    """

    video: TcpSpec | None
    foxglove: TcpSpec | None
    foxglove_where: str
    line: str | None


def check_views(video: str | None, foxglove: str | None, config_address: str,
                insecure: bool) -> Views:
    """Check ``--video`` and ``--foxglove`` (else the config's ``[foxglove] address``).

    Raises:
        InputError: a value that is not an address, a port out of 0-65535, or live topics
            open to the network without ``insecure`` (one line naming the option).
        TransportError: a host that does not resolve.
    """
    video_spec = (None if video is None
                  else parse_http_spec(video, "--video", DEFAULT_VIDEO_PORT))
    option, text = (("--foxglove", foxglove) if foxglove is not None
                    else ("[foxglove] address", config_address))
    if not text:
        return Views(video_spec, None, "", None)
    spec = tcp_spec(option, text, text, FOXGLOVE_PORT)
    where = f"{option} {text}"
    if is_loopback(resolve_ipv4(where, spec.host, spec.port)[0]):
        return Views(video_spec, spec, where, None)
    if not insecure:
        raise InputError(where, "live topics open to the network show anyone who reaches them "
                         "the camera and where the robot goes (nobody signs in): serve them "
                         "on 127.0.0.1 and tunnel the port (ssh -L), or add --insecure")
    return Views(video_spec, spec, where, f"WARNING: live topics on {spec.host}:{spec.port} are "
                 "open to the network (--insecure): anyone who reaches them sees the camera "
                 "and where the robot goes")


def open_views(views: Views, config: VmnavConfig, unix_offset_ns: int,
               owned: contextlib.ExitStack) -> tuple[LiveView | None, FoxgloveBridge | None]:
    """Open the servers ``views`` asks for; ``owned`` closes them.

    Raises:
        TransportError: a server cannot listen (a port in use: one line naming the option).
    """
    from robot.video import LiveView
    from shared.mjpeg_server import MjpegServer

    live_view = None
    if views.video is not None:
        live_view = LiveView(owned.enter_context(MjpegServer(
            views.video.host, views.video.port, config.video.jpeg_quality,
            width_px=config.video.width_px, max_clients=config.video.max_clients)),
            config.video)
    bridge = None
    if views.foxglove is not None:
        from robot.foxglove_bridge import FoxgloveBridge

        bridge = owned.enter_context(FoxgloveBridge(
            views.foxglove.host, views.foxglove.port, config.foxglove, config.camera.mount,
            unix_offset_ns=unix_offset_ns, where=views.foxglove_where))
    return live_view, bridge
