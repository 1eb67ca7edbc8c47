"""The web app on a real ground station, a WebSocket client, and headless Chromium.

``web``: ``ground.web.server.WebServer`` in this process (its own thread) on a free port,
its station aimed by ``udpout`` at the ``vehicle`` fixture of ``tests/ground/conftest.py``
(a real vehicle endpoint with the tests' FakeApp). ``chromium``: Debian's Chromium through
its ChromeDriver, headless, with a fresh profile and nothing that reaches the network.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from ground.station import GroundStation
from ground.web.server import WebConfig, WebServer
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import WallClock

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
#: Generous: the machine is shared with benchmarks (a wait ends as soon as its condition holds).
WAIT_S = 60.0


def wait_for(done: Callable[[], Any], what: str, timeout_s: float = WAIT_S) -> Any:
    """Poll ``done()`` every 20 ms until it returns something true; that value.

    Raises:
        AssertionError: not within ``timeout_s``.
    """
    limit = time.monotonic() + timeout_s
    while not (value := done()):
        assert time.monotonic() < limit, f"{what}: not within {timeout_s:g} s"
        time.sleep(0.02)
    return value


class RunningWeb:
    """A :class:`WebServer` on its thread; :meth:`close` stops it.

    Args:
        station: the ground station it serves.
        options: :class:`WebConfig` fields other than the port (a free one).
    """

    def __init__(self, station: GroundStation, **options: Any) -> None:
        self.station = station
        self.server = WebServer(station, station.clock, WebConfig(port=0, **options))
        self.url = self.server.url
        self.ws_url = self.url.replace("http://", "ws://") + "ws"
        self._thread = threading.Thread(target=self.server.run, name="web-server")
        self._thread.start()
        wait_for(lambda: self.server.started or not self._thread.is_alive(), "server start")
        assert self.server.started

    def close(self) -> None:
        self.server.stop()
        self._thread.join(WAIT_S)
        assert not self._thread.is_alive()
        self.station.close()


@pytest.fixture
def web(vehicle: UdpVehicle, tmp_path: Path) -> Iterator[RunningWeb]:
    """The app on a free port; its ground log folder (``--log``) is ``tmp_path / "logs"``."""
    station = GroundStation.open(f"udpout:127.0.0.1:{vehicle.link.local_port}", WallClock())
    running = RunningWeb(station, log_dir=tmp_path / "logs")
    try:
        yield running
    finally:
        running.close()


class Page:
    """One WebSocket client of the app, as a page is (``websockets``' blocking client)."""

    def __init__(self, url: str, origin: str | None = None,
                 headers: dict[str, str] | None = None) -> None:
        from websockets.sync.client import connect

        headers = {**(headers or {}), **({"Origin": origin} if origin is not None else {})}
        self._opened = contextlib.ExitStack()
        self.ws = self._opened.enter_context(
            connect(url, additional_headers=headers, open_timeout=WAIT_S))
        self.hello = self.receive()
        assert self.hello["type"] == "hello"
        self.updates: list[dict[str, Any]] = []

    def receive(self) -> dict[str, Any]:
        return json.loads(self.ws.recv(timeout=WAIT_S))

    def send(self, text: str) -> None:
        self.ws.send(text)

    def reply(self) -> dict[str, Any]:
        """The next reply (updates before it are kept in :attr:`updates`)."""
        while (message := self.receive())["type"] != "reply":
            self.updates.append(message)
        return message

    def ask(self, cmd: str, **fields: Any) -> dict[str, Any]:
        """Send a request and return its reply."""
        self.send(json.dumps({"cmd": cmd, **fields}))
        return self.reply()

    def update_where(self, done: Callable[[dict[str, Any]], bool], what: str) -> dict[str, Any]:
        """The first update from now on for which ``done(update)``."""
        limit = time.monotonic() + WAIT_S
        while True:
            assert time.monotonic() < limit, f"{what}: no such update within {WAIT_S:g} s"
            message = self.receive()
            if message["type"] == "update" and done(message):
                return message

    def close(self) -> None:
        self._opened.close()


@pytest.fixture
def page(web: RunningWeb) -> Iterator[Page]:
    client = Page(web.ws_url)
    try:
        yield client
    finally:
        client.close()


@pytest.fixture
def chromium(tmp_path: Path) -> Iterator[Any]:
    """Headless Chromium via ChromeDriver (selenium); skipped when Debian's packages are
    missing (``make test`` installs them)."""
    if not (CHROMIUM.exists() and CHROMEDRIVER.exists()):
        pytest.skip(f"needs {CHROMIUM} and {CHROMEDRIVER} (apt-get install chromium "
                    "chromium-driver; `make test` does)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage",
                 f"--user-data-dir={tmp_path / 'chromium-profile'}", "--window-size=1280,1400"):
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(str(CHROMEDRIVER)))
    driver.set_page_load_timeout(WAIT_S)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(tmp_path / "chromium-profile", ignore_errors=True)


def console_errors(driver: Any) -> list[str]:
    """The browser console's errors since the last call."""
    return [entry["message"] for entry in driver.get_log("browser")
            if entry["level"] == "SEVERE"]
