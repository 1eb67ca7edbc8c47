"""``vmnav pioneer``: our ARIA driver against the emulated Pioneer, in real time, over real
TCP and a real pty; a client killed mid-motion does not block the next one."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from shared.clock import WallClock
from shared.pose import Pose2
from sim.config import SimConfig
from sim.pioneer import EmulatedPioneer, PioneerServer, PtyLink, TcpListener
from sim.simulation import Simulation
from sim.world import load_world
from tools.cli import main

ODOMETRY = re.compile(r"t +2\.0 s: odometry x ([-+.\d]+) m, y ([-+.\d]+) m, yaw ([-+.\d]+) deg, "
                      r"([.\d]+) m driven")


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[PioneerServer, str, str]]:
    """An emulated Pioneer in the lab's open corridor, on TCP (any port) and a pty, in real
    time on a thread; yields the server, the socket URL and the pty's symlink."""
    sim = Simulation(load_world("lab"), SimConfig(seed=2))
    sim.place_robot(Pose2(8.0, 10.0, 0.0))
    emulator = EmulatedPioneer(sim, sim.config.emulator, np.random.default_rng(0))
    listener = TcpListener("127.0.0.1", 0)
    pty = PtyLink(tmp_path / "pioneer")
    server = PioneerServer(emulator, links=[pty], listeners=[listener])
    thread = threading.Thread(target=server.run, args=(WallClock(),))
    thread.start()
    try:
        yield server, f"socket://127.0.0.1:{listener.port}", str(tmp_path / "pioneer")
    finally:
        server.stop()
        thread.join(timeout=5.0)
        server.close()


def drive(url: str, capsys: pytest.CaptureFixture[str]) -> tuple[float, float, float]:
    """Drive 0.2 m/s and 10 deg/s for 2 s; (distance m, yaw deg, x m) from the odometry."""
    code = main(["pioneer", "--aria", url, "--drive", "0.2", "10", "--duration", "2"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "connected to 'vmnav' (Pioneer p3at-sh)" in out and "0 bad checksums" in out
    found = ODOMETRY.search(out)
    assert found is not None, out
    x, _, yaw, distance = (float(v) for v in found.groups())
    return distance, yaw, x


@pytest.mark.parametrize("transport", ["tcp", "pty"])
def test_drives_the_emulator_within_a_quarter_of_the_command(
    served: tuple[PioneerServer, str, str], transport: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    server, tcp_url, pty_path = served
    distance, yaw, _ = drive(tcp_url if transport == "tcp" else pty_path, capsys)
    assert distance == pytest.approx(0.4, rel=0.25)  # 0.2 m/s for 2 s, from rest
    assert yaw == pytest.approx(20.0, rel=0.25)
    assert server.emulator.state.name != "OPEN"  # the driver closed the link


def test_a_client_killed_mid_motion_leaves_the_robot_to_the_next(
    served: tuple[PioneerServer, str, str], capsys: pytest.CaptureFixture[str],
) -> None:
    server, tcp_url, _ = served
    victim = subprocess.Popen(
        [sys.executable, "-m", "tools.cli", "pioneer", "--aria", tcp_url, "--drive", "0.3", "0",
         "--duration", "30"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert victim.stdout is not None
        assert "connected" in victim.stdout.readline()
        time.sleep(1.5)  # moving now
        victim.send_signal(signal.SIGKILL)  # no CLOSE, no stop
        victim.wait(timeout=5.0)
    finally:
        victim.kill()
    body = server.emulator.simulation.body
    distance, _, _ = drive(tcp_url, capsys)
    assert distance == pytest.approx(0.4, rel=0.25)
    assert math.hypot(*body.velocity_base[:2]) < 0.05  # stopped again after the CLOSE


def test_a_missing_device_is_one_line_naming_it(capsys: pytest.CaptureFixture[str],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("robot.pioneer.connection.CONNECT_TIMEOUT_S", 1.0)
    code = main(["pioneer", "--aria", "/dev/ttyNOPE"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1
    assert "/dev/ttyNOPE: no Pioneer ready within 1 s" in err and "could not open port" in err
