"""uvicorn serving the web app (``ground.web.app``) on a socket bound here, with the station
loop running while it serves.

The page can drive the robot, so who may open it is checked (``ground.web.access``):
without an access token only loopback addresses are served (and only loopback names in
``Host``); any other address requires a token, which every request and WebSocket must
carry. The URL announced at start carries it (``?token=``).
"""

from __future__ import annotations

import logging
import socket
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import uvicorn

from ground.station import GroundStation
from ground.web.access import AccessGate
from ground.web.app import Hub, build_app
from ground.web.station_loop import StationLoop
from shared.clock import Clock
from shared.errors import InputError
from shared.guarded_http import is_loopback_name

#: How long a stopping server waits for open pages to close, s.
GRACEFUL_S = 2


@dataclass(frozen=True, slots=True)
class WebConfig:
    """Where and how to serve.

    Attributes:
        host: the address to bind; other than loopback only with a ``token``.
        port: the TCP port; 0 picks a free one.
        vehicle_timeout_s: how long a request waits for a vehicle not heard yet, s.
        token: the access token every request must carry; None: loopback only.
        log_dir: the ground log's folder (``--log``), listed in the page; None: no log.
    """

    host: str = "127.0.0.1"
    port: int = 8080
    vehicle_timeout_s: float = 5.0
    token: str | None = None
    log_dir: Path | None = None


def check_loopback(host: str, where: str = "--http") -> None:
    """Refuse a host that is not a loopback address, for a server without a token.

    Raises:
        InputError: ``host`` is not ``localhost`` or a loopback IP address.
    """
    if not is_loopback_name(host):
        raise InputError(where, f"{host} is not a loopback address: serving another address "
                                "needs an access token (--token-file, or one generated)")


class WebServer:
    """The app on a bound socket, run by :meth:`run` until :meth:`stop` or a signal.

    Args:
        station: the ground station (the loop's from :meth:`run` on).
        clock: the station's clock.
        config: where to serve.

    Raises:
        InputError: a host that is not loopback, without a token.
        TransportError: the port cannot be bound.
    """

    def __init__(self, station: GroundStation, clock: Clock, config: WebConfig) -> None:
        from shared.errors import TransportError

        if config.token is None:
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
        self.entry_url = self.url if config.token is None else f"{self.url}?token={config.token}"
        """The address to open: the page's, with the token if there is one."""
        self.hub = Hub()
        self.station_loop = StationLoop(station, clock, self.hub.publish_threadsafe,
                                        config.vehicle_timeout_s)
        app = AccessGate(build_app(self.station_loop, self.hub, config.log_dir), config.token)
        self._server = uvicorn.Server(uvicorn.Config(
            app, log_level=logging.WARNING,
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
    announce(f"serving {server.entry_url} (MAVLink on {where}); Ctrl-C stops")
    server.run()
