"""uvicorn serving the web app (``ground.web.app``) on a socket bound here, with the station
loop running while it serves.

Only loopback addresses are served: the app has no access token yet (issue 18's
``--bind`` with a token is still to come), and the page can drive the robot. From another
machine, use an SSH tunnel (``ssh -L 8080:127.0.0.1:8080 groundpc``).
"""

from __future__ import annotations

import ipaddress
import logging
import socket
from collections.abc import Callable
from dataclasses import dataclass

import uvicorn

from ground.station import GroundStation
from ground.web.app import Hub, build_app
from ground.web.station_loop import StationLoop
from shared.clock import Clock
from shared.errors import InputError

#: How long a stopping server waits for open pages to close, s.
GRACEFUL_S = 2


@dataclass(frozen=True, slots=True)
class WebConfig:
    """Where and how to serve.

    Attributes:
        host: the address to bind, loopback only (module docstring).
        port: the TCP port; 0 picks a free one.
        vehicle_timeout_s: how long a request waits for a vehicle not heard yet, s.
    """

    host: str = "127.0.0.1"
    port: int = 8080
    vehicle_timeout_s: float = 5.0


def check_loopback(host: str, where: str = "--http") -> None:
    """Refuse a host that is not a loopback address (module docstring).

    Raises:
        InputError: ``host`` is not ``localhost`` or a loopback IP address.
    """
    try:
        loopback = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        loopback = False
    if not loopback:
        raise InputError(where, f"{host} is not a loopback address: the web app has no access "
                                "token yet, so it serves this machine only (use an SSH tunnel)")


class WebServer:
    """The app on a bound socket, run by :meth:`run` until :meth:`stop` or a signal.

    Args:
        station: the ground station (the loop's from :meth:`run` on).
        clock: the station's clock.
        config: where to serve.

    Raises:
        InputError: a host that is not loopback.
        TransportError: the port cannot be bound.
    """

    def __init__(self, station: GroundStation, clock: Clock, config: WebConfig) -> None:
        from shared.errors import TransportError

        check_loopback(config.host)
        family = socket.AF_INET6 if ":" in config.host else socket.AF_INET
        self._socket = socket.socket(family, socket.SOCK_STREAM)
        self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._socket.bind((config.host, config.port))
            # Listening from here on: a page opened as soon as the URL is printed waits in
            # the backlog until uvicorn accepts, instead of being refused.
            self._socket.listen(128)
        except OSError as e:
            self._socket.close()
            raise TransportError(f"--http {config.host}:{config.port}",
                                 e.strerror or str(e)) from None
        host, port = self._socket.getsockname()[:2]
        self.url = f"http://[{host}]:{port}/" if family == socket.AF_INET6 else \
            f"http://{host}:{port}/"
        """The page's address."""
        self.hub = Hub()
        self.station_loop = StationLoop(station, clock, self.hub.publish_threadsafe,
                                        config.vehicle_timeout_s)
        self._server = uvicorn.Server(uvicorn.Config(
            build_app(self.station_loop, self.hub), log_level=logging.WARNING,
            timeout_graceful_shutdown=GRACEFUL_S, ws="websockets-sansio", lifespan="on"))

    @property
    def started(self) -> bool:
        """The server accepts connections."""
        return self._server.started

    def run(self) -> None:
        """Serve until :meth:`stop` (or SIGINT/SIGTERM when run on the main thread)."""
        try:
            self._server.run(sockets=[self._socket])
        finally:
            self._socket.close()

    def stop(self) -> None:
        """Ask :meth:`run` to return (from any thread)."""
        self._server.should_exit = True


def serve(station: GroundStation, clock: Clock, config: WebConfig,
          announce: Callable[[str], None]) -> None:
    """Serve the web app until Ctrl-C or SIGTERM; ``announce`` gets the line with its URL."""
    server = WebServer(station, clock, config)
    port = getattr(station.link, "local_port", None)  # a serial radio has none
    where = station.link.url if port is None else f"{station.link.url}, port {port}"
    announce(f"serving {server.url} (MAVLink on {where}); Ctrl-C stops")
    server.run()
