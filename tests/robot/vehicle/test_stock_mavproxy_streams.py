"""Stock MAVProxy (a subprocess) against the vehicle on a stream: over TCP both ways
(``--master=tcp:`` to the robot's ``tcpin:``, ``--master=tcpin:`` called by the robot's
``tcp:``) and over a serial radio pair (``--master=DEVICE --baudrate 57600``). MAVProxy
detects the vehicle, names its mode, downloads every parameter, and a ``param set``
reaches the robot's application."""

from __future__ import annotations

import importlib.util
import socket
from pathlib import Path

import pytest

from robot.vehicle.robot_params import ROBOT_PARAMS
from shared.mavlink.dialect import to_float32
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.mavproxy_console import MavproxyConsole, wait_until
from tests.robot.vehicle.stream_rig import Radios, start_vehicle

if importlib.util.find_spec("MAVProxy") is None:
    pytest.skip("MAVProxy is not installed (it comes with pip install -e '.[dev]')",
                allow_module_level=True)


def free_tcp_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def check_session(master: str, home: Path, app: FakeApp, *extra: str) -> None:
    """MAVProxy on ``master``: vehicle detected, mode named, parameters, one set applied."""
    console = MavproxyConsole(master, home, *extra)
    try:
        console.expect(r"Detected vehicle 1:1 on link 0", timeout_s=30)
        console.expect(r"Mode MANUAL$")
        console.expect(rf"Received {len(ROBOT_PARAMS)} parameters$", timeout_s=30)
        console.send("param set CTL_SPEED 0.3")
        wait_until(lambda: app.configs[-1].control.speed_m_s == to_float32(0.3),
                   "the vehicle applies the new value")
    finally:
        console.close()


@pytest.mark.slow
def test_mavproxy_calls_the_robot_over_tcp(tmp_path: Path) -> None:
    app = FakeApp()
    with start_vehicle(tmp_path, app, "tcpin:127.0.0.1:0") as vehicle:
        port = vehicle.link.local_port  # type: ignore[attr-defined]
        check_session(f"tcp:127.0.0.1:{port}", tmp_path, app)


@pytest.mark.slow
def test_the_robot_calls_mavproxy_over_tcp(tmp_path: Path) -> None:
    app = FakeApp()
    port = free_tcp_port()
    with start_vehicle(tmp_path, app, f"tcp:127.0.0.1:{port}"):  # retries until it listens
        check_session(f"tcpin:127.0.0.1:{port}", tmp_path, app)


@pytest.mark.slow
def test_mavproxy_over_a_serial_radio_pair(tmp_path: Path) -> None:
    app = FakeApp()
    radios = Radios(tmp_path)
    try:
        with start_vehicle(tmp_path, app, f"serial:{radios.robot_path}:57600"):
            check_session(str(radios.ground_path), tmp_path, app, "--baudrate=57600")
    finally:
        radios.close()
