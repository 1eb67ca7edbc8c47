"""``vmnav ground web``: its defaults as a process, and its refusals in one line."""

from __future__ import annotations

import contextlib
import re
import socket
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from shared.clock import WallClock
from tests.ground.web.conftest import Page, wait_for
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle
from tools.cli import build_parser, main
from tools.harness.vmnav_process import VmnavProcess


def free(kind: int, port: int) -> bool:
    """Whether 127.0.0.1:``port`` can be bound (TCP or UDP)."""
    with contextlib.closing(socket.socket(socket.AF_INET, kind)) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def test_the_defaults_serve_the_page_on_8080_and_listen_for_mavlink_on_14550(
        tmp_path: Path) -> None:
    if not (free(socket.SOCK_STREAM, 8080) and free(socket.SOCK_DGRAM, 14550)):
        pytest.skip("127.0.0.1:8080/tcp or 127.0.0.1:14550/udp is taken on this machine")
    web = VmnavProcess(["ground", "web"], tmp_path / "web.out", 15.0)
    try:
        wait_for(lambda: "serving" in web.output() or web.process.poll() is not None,
                 "vmnav ground web started")
        assert re.search(r"^vmnav ground web: serving http://127\.0\.0\.1:8080/ \(MAVLink on "
                         r"udpin:127\.0\.0\.1:14550, port 14550\); Ctrl-C stops$",
                         web.output(), re.M), web.output()
        with urllib.request.urlopen("http://127.0.0.1:8080/", timeout=60) as response:
            assert b"<title>vmnav ground</title>" in response.read()
        # A robot sending to the default port (`vmnav robot --mavlink udpout:127.0.0.1:14550`;
        # here its vehicle endpoint) shows in the fleet.
        with make_vehicle(tmp_path, FakeApp(), WallClock(), url="udpout:127.0.0.1:14550") as v:
            v.start_thread()
            page = Page("ws://127.0.0.1:8080/ws")
            try:
                page.update_where(lambda u: [x["system_id"] for x in u["vehicles"]] == [1],
                                  "vehicle 1 in the fleet")
            finally:
                page.close()
    finally:
        code = web.stop()
    assert code == 143 and "Traceback" not in web.output()  # SIGTERM, as Ctrl-C: clean


def test_http_parses_host_and_port() -> None:
    args = build_parser().parse_args(["ground", "web", "--http", "[::1]:0"])
    assert args.http == ("::1", 0)
    assert build_parser().parse_args(["ground", "web"]).http == ("127.0.0.1", 8080)


@pytest.mark.parametrize("http", ["8080", "localhost:", "127.0.0.1:99999", ":80"])
def test_a_bad_address_is_a_usage_error(http: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["ground", "web", "--http", http])
    assert exited.value.code == 2
    assert f"argument --http: expected HOST:PORT, e.g. 127.0.0.1:8080, got '{http}'" in \
        capsys.readouterr().err


def test_a_bad_token_file_is_refused_before_connecting(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "token").write_text("short\n")
    assert main(["ground", "--connect", "udpin:127.0.0.1:0", "web",
                 "--http", "0.0.0.0:0", "--token-file", str(tmp_path / "token")]) == 1
    assert capsys.readouterr().err == (
        f"vmnav ground: error: {tmp_path / 'token'}: the token must be at least 16 characters "
        "of letters, digits and -._~ (no spaces)\n")


def test_an_address_open_to_the_network_gets_a_token(tmp_path: Path) -> None:
    web = VmnavProcess(["ground", "--connect", "udpin:127.0.0.1:0", "web", "--http",
                        "0.0.0.0:0"], tmp_path / "web.out", 15.0)
    try:
        line = wait_for(lambda: re.search(
            r"^vmnav ground web: serving http://0\.0\.0\.0:(\d+)/\?token=([A-Za-z0-9_-]{32}) ",
            web.output(), re.M) or web.process.poll() is not None, "vmnav ground web started")
        assert line is not True, web.output()
        port, token = line.groups()
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=60)
            raise AssertionError("served without the token")
        except urllib.error.HTTPError as e:
            assert e.code == 401
        opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
        with opener.open(f"http://127.0.0.1:{port}/?token={token}", timeout=60) as response:
            assert response.url == f"http://127.0.0.1:{port}/"  # the token left the address
            assert b"<title>vmnav ground</title>" in response.read()
    finally:
        code = web.stop()
    assert code == 143 and "Traceback" not in web.output()
