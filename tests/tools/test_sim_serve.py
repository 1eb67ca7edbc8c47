"""``vmnav sim serve``: arguments, where it serves, a client end to end, clean exits."""

from __future__ import annotations

import re
import socket
import threading
import time
from pathlib import Path

import pytest

from shared.errors import InputError
from tests.sim.pioneer.test_server import connect_and_drive, tcp_client
from tools.cli import main
from tools.sim_serve import PtySpec, TcpSpec, parse_aria_spec


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


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


class TestServe:
    def test_serves_on_tcp_for_the_duration(self, capsys: pytest.CaptureFixture[str]) -> None:
        code, out, _ = run(["sim", "serve", "--duration", "1", "--aria", "tcp:0"], capsys)
        assert code == 0
        port = int(re.search(r"ARIA on tcp 127\.0\.0\.1:(\d+)", out).group(1))  # type: ignore[union-attr]
        assert port > 0
        assert "stopped after 1.0 s" in out

    def test_a_client_drives_the_served_robot(self, capsys: pytest.CaptureFixture[str]) -> None:
        probe = socket.socket()
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
        probe.close()
        failures: list[BaseException] = []

        def client() -> None:
            try:
                for _ in range(200):  # until the server listens (it builds the world first)
                    try:
                        host = tcp_client(port)
                        break
                    except ConnectionRefusedError:
                        time.sleep(0.02)
                connect_and_drive(host)
                host.link.close()
            except BaseException as e:  # reported to the test's thread
                failures.append(e)

        thread = threading.Thread(target=client)
        thread.start()
        code, out, _ = run(["sim", "serve", "--duration", "2.5", "--aria", f"tcp:{port}"], capsys)
        thread.join(timeout=5.0)
        assert not thread.is_alive() and failures == []
        assert code == 0
        sips = int(re.search(r"(\d+) SIPs", out).group(1))  # type: ignore[union-attr]
        assert sips >= 6

    @pytest.mark.parametrize(
        ("args", "fragment"),
        [
            (["--aria", "serial:/dev/ttyS0"], "--aria: 'serial:/dev/ttyS0' is not"),
            (["--aria", "tcp:99999"], "--aria: 'tcp:99999': the TCP port"),
            (["--duration", "0"], "--duration: must be > 0"),
        ],
    )
    def test_bad_arguments(
        self, args: list[str], fragment: str, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code, out, err = run(["sim", "serve", *args], capsys)
        assert code == 1 and out == ""
        assert err.count("\n") == 1 and fragment in err

    def test_port_in_use(self, capsys: pytest.CaptureFixture[str]) -> None:
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen(1)
            port = taken.getsockname()[1]
            code, _, err = run(["sim", "serve", "--aria", f"tcp:{port}"], capsys)
        assert code == 1
        assert err.count("\n") == 1 and f"tcp:127.0.0.1:{port}: cannot listen" in err
