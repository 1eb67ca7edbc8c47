"""``vmnav sim serve``: arguments, where it serves, a client end to end, clean exits."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from robot.camera import VideoCaptureSource
from robot.config import CameraSourceConfig
from shared.camera_model import CameraModel
from shared.clock import WallClock
from shared.errors import InputError
from tests.sim.pioneer.aria_host import AriaHost
from tests.sim.pioneer.test_server import (
    PATIENCE_S,
    connect,
    connect_and_drive,
    pump,
    tcp_client,
)
from tools.cli import main
from tools.sim_serve_cmd import PtySpec, TcpSpec, parse_aria_spec, parse_video_spec

ROOT = Path(__file__).resolve().parents[2]


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def serve_to_a_client(session: Callable[[AriaHost], None],
                      capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """``vmnav sim serve`` on a free TCP port in this process, while a client thread
    connects (once it listens), runs ``session`` and stops the server by SIGTERM, as a
    user would; the server's exit code and output. ``--duration`` only bounds a hang."""
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    failures: list[BaseException] = []

    def client() -> None:
        give_up = time.monotonic() + PATIENCE_S
        try:
            while True:  # until the server listens (it builds the world first)
                try:
                    host = tcp_client(port)
                    break
                except ConnectionRefusedError:
                    if time.monotonic() > give_up:
                        raise
                    time.sleep(0.02)
            session(host)
            host.link.close()
            os.kill(os.getpid(), signal.SIGTERM)  # the server's handler stops it
        except BaseException as e:  # reported to the test's thread
            failures.append(e)

    thread = threading.Thread(target=client)
    thread.start()
    code, out, _ = run(["sim", "serve", "--duration", str(3 * PATIENCE_S),
                        "--aria", f"tcp:{port}"], capsys)
    thread.join(timeout=PATIENCE_S)
    assert not thread.is_alive() and failures == []
    return code, out


class TestAriaSpec:
    @pytest.mark.parametrize(
        ("text", "spec"),
        [
            ("pty", PtySpec()),
            ("pty:/tmp/robot", PtySpec(Path("/tmp/robot"))),
            ("tcp", TcpSpec("127.0.0.1", 8101)),
            ("tcp:0", TcpSpec("127.0.0.1", 0)),
            ("tcp:0.0.0.0:9000", TcpSpec("0.0.0.0", 9000)),
        ],
    )
    def test_valid(self, text: str, spec: PtySpec | TcpSpec) -> None:
        assert parse_aria_spec(text) == spec

    @pytest.mark.parametrize("text", ["serial", "tcp:http", "tcp:70000", "tcp:-1", ""])
    def test_invalid(self, text: str) -> None:
        with pytest.raises(InputError, match="--aria"):
            parse_aria_spec(text)


class TestVideoSpec:
    @pytest.mark.parametrize(
        ("text", "spec"),
        [
            ("http", TcpSpec("127.0.0.1", 8080)),
            ("http:0", TcpSpec("127.0.0.1", 0)),
            ("http:0.0.0.0:9000", TcpSpec("0.0.0.0", 9000)),
        ],
    )
    def test_valid(self, text: str, spec: TcpSpec) -> None:
        assert parse_video_spec(text) == spec

    @pytest.mark.parametrize("text", ["tcp:8080", "http:x", "http:70000", ""])
    def test_invalid(self, text: str) -> None:
        with pytest.raises(InputError, match="--video"):
            parse_video_spec(text)


class TestServe:
    def test_serves_on_tcp_for_the_duration(self, capsys: pytest.CaptureFixture[str]) -> None:
        code, out, _ = run(["sim", "serve", "--duration", "1", "--aria", "tcp:0"], capsys)
        assert code == 0
        port = int(re.search(r"ARIA on tcp 127\.0\.0\.1:(\d+)", out).group(1))  # type: ignore[union-attr]
        assert port > 0
        assert "stopped after 1.0 s" in out

    def test_a_client_drives_the_served_robot(self, capsys: pytest.CaptureFixture[str]) -> None:
        code, out = serve_to_a_client(connect_and_drive, capsys)
        assert code == 0
        sips = int(re.search(r"(\d+) SIPs", out).group(1))  # type: ignore[union-attr]
        assert sips >= 6

    def test_battest_above_25_5_v_does_not_end_it(self, capsys: pytest.CaptureFixture[str]
                                                  ) -> None:
        """Issue 15: ``fa fb 06 fa 3b 00 01 fa 3c`` after the handshake ended the server."""

        def battest(host: AriaHost) -> None:
            connect(host)
            host.link.write(bytes.fromhex("fafb06fa3b0001fa3c"))
            start = len(host.sips)
            assert pump(host, PATIENCE_S, lambda: len(host.sips) - start >= 3)
            assert host.sips[-1][1].real_battery_v == pytest.approx(25.6)

        code, out = serve_to_a_client(battest, capsys)
        assert code == 0 and "0 handler errors" in out

    @pytest.mark.parametrize(
        ("args", "fragment"),
        [
            (["--aria", "serial:/dev/ttyS0"], "--aria: 'serial:/dev/ttyS0' is not"),
            (["--aria", "tcp:99999"], "--aria: 'tcp:99999': the TCP port"),
            (["--duration", "0"], "--duration: must be > 0"),
            (["--video", "udp:5000"], "--video: 'udp:5000' is not http:PORT"),
            (["--video", "http:0", "--jpeg-quality", "101"], "--jpeg-quality: must be 1-100"),
            (["--aria", "tcp:0", "--start", "1e9,0,0"],
             "--start: (1000000000.0, 0.0, 0.0 deg) is outside world 'lab' (x 0 to 30 m"),
            (["--aria", "tcp:0", "--start", "0,0,0"],
             "--start: (0.0, 0.0, 0.0 deg) overlaps a wall"),
            (["--aria", "tcp:0", "--route-start", "attic"],
             "--route-start: world 'lab' has no route 'attic' (routes: corridor, office_loop"),
        ],
    )
    def test_bad_arguments(
        self, args: list[str], fragment: str, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code, out, err = run(["sim", "serve", *args], capsys)
        assert code == 1 and out == ""
        assert err.count("\n") == 1 and fragment in err

    @pytest.mark.parametrize(("args", "where"), [
        ([], "at x 2.00 m, y 10.00 m, yaw 0.0 deg"),
        (["--start", "4.5,10,-90"], "at x 4.50 m, y 10.00 m, yaw -90.0 deg"),
        (["--route-start", "office_loop"], "at x 12.50 m, y 10.00 m, yaw 0.0 deg"),
    ])
    def test_start_pose(self, args: list[str], where: str,
                        capsys: pytest.CaptureFixture[str]) -> None:
        code, out, _ = run(["sim", "serve", "--duration", "0.1", "--aria", "tcp:0", *args], capsys)
        assert code == 0 and where in out.splitlines()[0]

    @pytest.mark.parametrize("text", ["1,2", "1,2,x", "nan,0,0", "1,2,3,4"])
    def test_bad_start_is_a_usage_error(self, text: str,
                                        capsys: pytest.CaptureFixture[str]) -> None:
        with pytest.raises(SystemExit) as exited:
            main(["sim", "serve", "--start", text])
        assert exited.value.code == 2 and "argument --start" in capsys.readouterr().err

    def test_port_in_use(self, capsys: pytest.CaptureFixture[str]) -> None:
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen(1)
            port = taken.getsockname()[1]
            code, _, err = run(["sim", "serve", "--aria", f"tcp:{port}"], capsys)
        assert code == 1
        assert err.count("\n") == 1 and f"tcp:127.0.0.1:{port}: cannot listen" in err

    def test_camera_port_in_use(self, capsys: pytest.CaptureFixture[str]) -> None:
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen(1)
            port = taken.getsockname()[1]
            code, _, err = run(["sim", "serve", "--aria", "tcp:0", "--video", f"http:{port}"],
                               capsys)
        assert code == 1
        assert err.count("\n") == 1 and f"http:127.0.0.1:{port}: cannot listen" in err

    def test_serves_the_camera_at_its_frame_rate(self, capsys: pytest.CaptureFixture[str]) -> None:
        code, out, _ = run(["sim", "serve", "--duration", "1", "--aria", "tcp:0",
                            "--video", "http:0"], capsys)
        assert code == 0
        assert re.search(r"camera on http://127\.0\.0\.1:\d+/stream\.mjpg \(one frame: "
                         r"http://127\.0\.0\.1:\d+/snapshot\.jpg\)", out)
        # 15 frames per second of simulation time (the first at the first step): 15 in the
        # 1 s of --duration on an idle machine; a loaded one simulates less of that second.
        simulated = re.search(r"stopped after ([\d.]+) s of simulation", out)
        frames = re.search(r"camera: (\d+) frames, 0 stream client\(s\)", out)
        assert simulated is not None and frames is not None, out
        count, simulated_s = int(frames.group(1)), float(simulated.group(1))
        assert count >= 1 and abs(count - 15 * simulated_s) <= 1  # 1: the rounding to 0.1 s


@pytest.mark.slow
def test_a_robot_reads_the_served_camera_then_sigterm_stops_cleanly() -> None:
    """Issue 8: the simulator in one process, the camera read as a network camera in another."""
    serve = subprocess.Popen(
        [sys.executable, "-m", "tools.cli", "sim", "serve", "--aria", "tcp:0", "--video",
         "http:0"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert serve.stdout is not None
        url = None
        while url is None and (line := serve.stdout.readline()):
            if found := re.search(r"camera on (\S+)", line):
                url = found.group(1)
        assert url is not None, serve.communicate(timeout=10.0)
        config = CameraSourceConfig(source=url, open_timeout_ns=3_000_000_000,
                                    read_timeout_ns=3_000_000_000)
        with VideoCaptureSource(config, WallClock(), CameraModel.default()) as camera:
            frames = [camera.read() for _ in range(3)]
        assert all(f is not None and f[1].shape == (600, 800) for f in frames)
        serve.send_signal(signal.SIGTERM)
        out, err = serve.communicate(timeout=10.0)
    finally:
        serve.kill()
    assert serve.returncode == 0, err
    assert "stopped after" in out and "1 stream client(s)" in out
