"""``vmnav bench web``: the web app's numbers of issue 18, in headless Chromium.

The ground station (``vmnav ground web``'s :class:`~ground.web.server.WebServer`) runs in
this process; vehicle 1 too (a :class:`~tools.bench.link_load.LinkLoadApp` this process
changes the mode of), and the others (``--vehicles``, 20 in all by default) in vehicle
processes (:mod:`tools.bench.link_vehicles`), all on loopback UDP. Debian's Chromium,
through ChromeDriver, opens the page with a fresh profile. Measured:

* ``first_load``: bytes transferred (navigation and resources, Resource Timing
  ``transferSize``) and the time to ``domInteractive`` and to the first fleet row;
* ``telemetry_to_dom_ms``: vehicle 1's mode changed in its application to the page's
  vehicle header showing it (a MutationObserver; one wall clock for both);
* ``goto_reply_ms``: the page's ``goto`` request to its reply, which comes after the
  vehicle's MISSION_ACK and MISSION_START's COMMAND_ACK (an upper bound of "go" to
  MISSION_ACK; each after a ``hold`` not timed);
* ``fleet``: main-thread time the page spends handling each update of the fleet
  (``App.handle``: the DOM rows and the plots' data; JSON parsing and drawing excluded),
  and this process's CPU over the window (the ground station, vehicle 1's I/O thread and
  the Selenium client, so an upper bound of the ground's).

* ``camera``: vehicle 1 serves the robot's live view at 640x480 (``--camera-hz``), the
  page shows it through the ground's relay: frames/s shown and latency, read back from
  numbers drawn into the frames (:mod:`tools.bench.web_camera`). It runs from the start
  and is measured right after the first load, then closed before the other figures.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from tools.bench.percentiles import percentile_summary
from tools.bench.web_camera import TARGETS as CAMERA_TARGETS

#: The issue's targets (figure -> comparison, bound), for ``bench all``.
TARGETS: dict[str, tuple[str, float]] = {
    "telemetry_to_dom_ms.p95": ("<", 150.0), "goto_reply_ms.p95": ("<", 100.0),
    "goto_reply_ms.refused": ("<=", 0), "fleet.update_main_thread_ms.max": ("<", 16.0),
    "fleet.process_cpu_share": ("<", 0.30), "first_load.bytes": ("<", 1_000_000),
    "first_load.interactive_ms": ("<", 1000.0)}
TARGETS.update(CAMERA_TARGETS)
_WAIT_S = 60.0


def _wait(done: Any, what: str) -> Any:
    limit = time.monotonic() + _WAIT_S
    while not (value := done()):
        if time.monotonic() > limit:
            raise TimeoutError(f"{what}: not within {_WAIT_S:g} s")
        time.sleep(0.01)
    return value


def _chromium(profile: Path) -> Any:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-dev-shm-usage", f"--user-data-dir={profile}",
                 "--window-size=1280,1400"):
        options.add_argument(flag)
    return webdriver.Chrome(options=options, service=Service("/usr/bin/chromedriver"))


def measure(args: argparse.Namespace) -> dict[str, Any]:
    """Run the measurements (module docstring); the JSON document."""
    from ground.station import GroundStation
    from ground.web.server import WebConfig, WebServer
    from shared.clock import WallClock
    from shared.mavlink.modes import Mode
    from tools.bench.link_load import make_load_app
    from tools.bench.link_vehicles import AppContext, VehicleProcesses, serve_vehicles
    from tools.bench.web_camera import CameraRobot

    station = GroundStation.open("udpin:127.0.0.1:0", WallClock())
    server = WebServer(station, station.clock, WebConfig(port=0))
    serving = threading.Thread(target=server.run, name="web", daemon=True)
    serving.start()
    apps: list[Any] = []
    stop = threading.Event()

    def factory(context: AppContext) -> Any:
        apps.append(make_load_app(context))
        return apps[-1]

    robot = CameraRobot(args.camera_hz)
    vehicle1 = threading.Thread(target=serve_vehicles, daemon=True, args=(
        [1], station.link.local_port, range(args.key_images), factory, stop.wait),
        kwargs={"video": robot.stream})
    with tempfile.TemporaryDirectory(prefix="vmnav-bench-web-") as tmp, VehicleProcesses(
            list(range(2, args.vehicles + 1)), 2, station.link.local_port, args.key_images,
            make_load_app), robot.running():
        vehicle1.start()
        _wait(lambda: server.started and apps, "the server and vehicle 1")
        driver = _chromium(Path(tmp) / "profile")
        try:
            started = time.monotonic()
            driver.get(server.url)
            _wait(lambda: driver.find_elements("css selector", "tr[data-system='1']"),
                  "vehicle 1 in the fleet")
            first_row_ms = (time.monotonic() - started) * 1000
            load = driver.execute_script(
                "const nav = performance.getEntriesByType('navigation')[0];"
                "const res = performance.getEntriesByType('resource');"
                "return [nav.transferSize + res.reduce((a, r) => a + r.transferSize, 0),"
                " nav.domInteractive];")
            _wait(lambda: len(driver.find_elements("css selector", "tr[data-system]"))
                  >= args.vehicles, "every vehicle in the fleet")
            camera = _watch_camera(driver, robot, args.camera_s)
            robot.server.close()
            driver.execute_script(
                "window.benchHandled = []; const app = window.vmnav, handle = app.handle.bind(app);"
                "app.handle = m => { const t0 = performance.now(); handle(m);"
                " if (m.type === 'update') window.benchHandled.push(performance.now() - t0); };"
                "window.benchModes = []; new MutationObserver(() => window.benchModes.push("
                "[document.getElementById('v-mode').textContent, performance.timeOrigin"
                " + performance.now()])).observe(document.getElementById('v-mode'),"
                " {childList: true, characterData: true, subtree: true});")
            cpu0, wall0 = time.process_time(), time.monotonic()
            latencies = []
            for i in range(args.changes):
                mode = Mode.MANUAL if i % 2 == 0 else Mode.HOLD
                sent_ms = time.time() * 1000
                apps[0].set_mode(mode)
                seen = _wait(lambda mode=mode, sent_ms=sent_ms: [
                    t for name, t in driver.execute_script("return window.benchModes")
                    if name == mode.name and t >= sent_ms],
                    f"mode {mode.name} in the page")
                latencies.append(seen[0] - sent_ms)
                time.sleep(0.2)
            cpu_share = (time.process_time() - cpu0) / (time.monotonic() - wall0)
            handled = driver.execute_script("return window.benchHandled")
            driver.set_script_timeout(_WAIT_S)
            replies = driver.execute_async_script(
                "const done = arguments[arguments.length - 1], out = [];"
                "(async () => { for (let i = 0; i < arguments[0]; i++) {"
                " await window.vmnav.link.request('hold', {system: 1});"
                " const t0 = performance.now();"
                " const r = await window.vmnav.link.request('goto', {system: 1, key: i % 10});"
                " out.push(r.ok ? performance.now() - t0 : -1); } done(out); })();",
                args.dispatches)
        finally:
            driver.quit()
            stop.set()
            server.stop()
            serving.join(_WAIT_S)
            station.close()
    return {
        "vehicles": args.vehicles,
        "first_load": {"bytes": load[0], "interactive_ms": round(load[1], 1),
                       "first_fleet_row_ms": round(first_row_ms, 1)},
        "telemetry_to_dom_ms": percentile_summary(latencies),
        "goto_reply_ms": {**percentile_summary([r for r in replies if r >= 0]),
                          "refused": sum(r < 0 for r in replies)},
        "fleet": {"updates": len(handled),
                  "update_main_thread_ms": percentile_summary(handled),
                  "process_cpu_share": round(cpu_share, 3)},
        "camera": camera,
        "targets": {figure: f"{comparison} {bound:g}"
                    for figure, (comparison, bound) in TARGETS.items()},
    }


def _watch_camera(driver: Any, robot: Any, window_s: float) -> dict[str, Any]:
    """Select vehicle 1, show its camera and read the frames back for ``window_s``
    (:mod:`tools.bench.web_camera`); its figures."""
    from tools.bench.web_camera import SAMPLER_JS, camera_figures

    driver.find_element("css selector", "tr[data-system='1']").click()
    _wait(lambda: "640x480" in driver.find_element("id", "camera-caption").text,
          "vehicle 1's camera in the page")
    driver.execute_script(SAMPLER_JS)
    _wait(lambda: driver.execute_script("return window.benchFrames.length"),
          "a numbered frame in the page")
    time.sleep(window_s)
    shown = driver.execute_script("clearInterval(window.benchSampler);"
                                  "return window.benchFrames")
    return camera_figures(shown, dict(robot.sent_ms), window_s)


def run(args: argparse.Namespace) -> int:
    """Print the web benchmark's JSON (``vmnav bench web``)."""
    from shared.errors import InputError

    if not (Path("/usr/bin/chromium").exists() and Path("/usr/bin/chromedriver").exists()):
        raise InputError("vmnav bench web", "needs Debian's chromium and chromium-driver "
                                            "(make browser installs them)")
    print(json.dumps(measure(args), indent=2))
    return 0
