"""``vmnav pioneer``: our ARIA driver against the emulated Pioneer, in real time, over real
TCP and a real pty; a client killed mid-motion does not block the next one."""

from __future__ import annotations

import contextlib
import math
import os
import re
import signal
import socket
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
    time on a thread; yields the server, its TCP address and the pty's symlink."""
    sim = Simulation(load_world("lab"), SimConfig(seed=2))
    sim.place_robot(Pose2(8.0, 10.0, 0.0))
    emulator = EmulatedPioneer(sim, sim.config.emulator, np.random.default_rng(0))
    listener = TcpListener("127.0.0.1", 0)
    pty = PtyLink(tmp_path / "pioneer")
    server = PioneerServer(emulator, links=[pty], listeners=[listener])
    thread = threading.Thread(target=server.run, args=(WallClock(),))
    thread.start()
    try:
        yield server, f"tcp:127.0.0.1:{listener.port}", str(tmp_path / "pioneer")
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


@pytest.mark.parametrize("transport", ["tcp", "socket", "pty", "device path"])
def test_drives_the_emulator_within_a_quarter_of_the_command(
    served: tuple[PioneerServer, str, str], transport: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The address forms: tcp:HOST:PORT, pty:PATH, and the old socket:// and device path."""
    server, tcp_url, pty_path = served
    aria = {"tcp": tcp_url, "socket": tcp_url.replace("tcp:", "socket://"),
            "pty": f"pty:{pty_path}", "device path": pty_path}[transport]
    distance, yaw, _ = drive(aria, capsys)
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
    # Stopped again after the CLOSE: the emulator reads it at its next tick and brakes at
    # 0.6 m/s^2 (a third of a second), well before its 2 s watchdog would stop it.
    deadline = time.monotonic() + 1.5
    while math.hypot(*body.velocity_base[:2]) >= 0.05 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert math.hypot(*body.velocity_base[:2]) < 0.05




@pytest.fixture
def unanswered_port() -> Iterator[int]:
    """A TCP port on loopback whose connects hang: its listener's backlog is full, so the
    kernel drops further SYNs, as a host that is down or firewalled does."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(0)
    port = server.getsockname()[1]
    held = []
    for _ in range(3):  # fills the queue of a backlog-0 listener
        client = socket.socket()
        client.setblocking(False)
        with contextlib.suppress(BlockingIOError):
            client.connect(("127.0.0.1", port))
        held.append(client)
    try:
        yield port
    finally:
        for sock in [*held, server]:
            sock.close()


def free_port() -> int:
    """A TCP port on loopback that nothing listens on (connects are refused)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.mark.parametrize(("kind", "problem"), [
    ("missing device", "no such device"),
    ("missing serial device", "no such device"),
    ("refused port", "Connection refused"),
    ("old refused port", "Connection refused"),
    ("unanswered host", "no answer from 127.0.0.1"),
])
def test_an_unreachable_pioneer_is_one_line_in_under_2_s(
        kind: str, problem: str, unanswered_port: int,
        capsys: pytest.CaptureFixture[str]) -> None:
    aria = {"missing device": "/dev/ttyNOPE", "missing serial device": "serial:/dev/ttyNOPE:9600",
            "refused port": f"tcp:127.0.0.1:{free_port()}",
            "old refused port": f"socket://127.0.0.1:{free_port()}",
            "unanswered host": f"tcp:127.0.0.1:{unanswered_port}"}[kind]
    start = time.monotonic()
    code = main(["pioneer", "--aria", aria])
    elapsed_s = time.monotonic() - start
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1, err
    assert f"--aria {aria}: " in err and problem in err
    assert elapsed_s < 5.0  # measured about 0.01 s, and 1.5 s (the connect timeout) unanswered


@pytest.mark.parametrize(("aria", "problem"), [
    ("tcp:8101", "expected tcp:HOST:PORT"),
    ("udpin:127.0.0.1:8101", "udpin:HOST:PORT cannot be used here"),
    ("serial:/dev/ttyUSB0:12", "baud rate 12 is not in 50..4000000"),
    ("tcp:127.0.0.1:0", "port '0' is not an integer in 1..65535"),
    ("pty:", "no pty path"),
])
def test_a_bad_aria_address_is_one_line_naming_it(aria: str, problem: str,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["pioneer", "--aria", aria])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and f"--aria: {aria!r}: {problem}" in err, err


@pytest.mark.slow
def test_sim_serve_and_pioneer_read_alike(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    """docs/links.md: ``vmnav sim serve --aria tcp:PORT --aria pty:PATH``, then ``vmnav
    pioneer --aria tcp:127.0.0.1:PORT`` and ``--aria pty:PATH`` (port 0 here: any free)."""
    from tests.tools.processes import start, wait_for

    link, log = tmp_path / "vmnav_pioneer", tmp_path / "sim.out"
    sim = start(["sim", "serve", "--aria", "tcp:0", "--aria", f"pty:{link}"], log)
    try:
        port = wait_for(r"ARIA on tcp 127\.0\.0\.1:(\d+)", log, sim).group(1)
        wait_for(r"ARIA on pty ", log, sim)
        for aria in (f"tcp:127.0.0.1:{port}", f"pty:{link}"):
            drive(aria, capsys)
    finally:
        sim.send_signal(signal.SIGTERM)
        sim.wait(15)
