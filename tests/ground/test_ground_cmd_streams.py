"""``vmnav ground --connect`` on streams: ``tcp:``, ``tcpin:``, ``serial:`` and ``pty:``
against the real vehicle endpoint (FakeApp) on a StreamVehicle; bad, refused and missing
addresses are one line, in well under 2 s; a robot that goes away ends ``watch`` with
one line."""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.stream_rig import Radios, start_vehicle
from tools.cli import main

Capsys = pytest.CaptureFixture[str]
STATUS = re.compile(r"vehicle 1: mode MANUAL, .* heartbeat \d+\.\d s ago\n")


def one_line_error(capsys: Capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("vmnav ground: error: "), err
    return err


def free_tcp_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def radios(tmp_path: Path) -> Iterator[Radios]:
    pair = Radios(tmp_path)
    yield pair
    pair.close()


def test_status_over_tcp(tmp_path: Path, capsys: Capsys) -> None:
    with start_vehicle(tmp_path, FakeApp(), "tcpin:127.0.0.1:0") as vehicle:
        port = vehicle.link.local_port  # type: ignore[attr-defined]
        assert main(["ground", "--connect", f"tcp:127.0.0.1:{port}", "status"]) == 0
    assert STATUS.fullmatch(capsys.readouterr().out)


def test_status_over_tcpin_called_by_the_robot(tmp_path: Path, capsys: Capsys) -> None:
    port = free_tcp_port()
    with start_vehicle(tmp_path, FakeApp(), f"tcp:127.0.0.1:{port}"):
        assert main(["ground", "--connect", f"tcpin:127.0.0.1:{port}", "status"]) == 0
    assert STATUS.fullmatch(capsys.readouterr().out)


@pytest.mark.parametrize("form", ["serial", "pty"])
def test_status_over_a_radio(tmp_path: Path, radios: Radios, form: str,
                             capsys: Capsys) -> None:
    robot = {"serial": f"serial:{radios.robot_path}:57600", "pty": f"pty:{radios.robot_path}"}
    ground = {"serial": f"serial:{radios.ground_path}:57600",
              "pty": f"pty:{radios.ground_path}"}
    with start_vehicle(tmp_path, FakeApp(), robot[form]):
        assert main(["ground", "--connect", ground[form], "status"]) == 0
    assert STATUS.fullmatch(capsys.readouterr().out)


def test_watch_ends_in_one_line_when_the_robot_goes(tmp_path: Path, capsys: Capsys) -> None:
    vehicle = start_vehicle(tmp_path, FakeApp(), "tcpin:127.0.0.1:0")
    port = vehicle.link.local_port  # type: ignore[attr-defined]

    def close_once_heard() -> None:  # the robot goes while watch runs
        limit = time.monotonic() + 30.0
        while vehicle.endpoint.stats().messages == 0 and time.monotonic() < limit:
            time.sleep(0.01)
        vehicle.close()

    threading.Thread(target=close_once_heard, daemon=True).start()
    code = main(["ground", "--connect", f"tcp:127.0.0.1:{port}", "watch", "--duration", "60"])
    assert code == 1
    assert one_line_error(capsys).endswith(f"tcp:127.0.0.1:{port}: closed by the peer\n")


@pytest.mark.parametrize(("connect", "problem"), [
    ("tcp:5760", "--connect: 'tcp:5760': expected tcp:HOST:PORT (a host and a port)"),
    ("serial:", "--connect: 'serial:': no device"),
    ("http:127.0.0.1:80", "--connect: 'http:127.0.0.1:80': not a link address"),
    ("socket://127.0.0.1:5760", "a URL is not a link address here"),
    ("tcpin:0.0.0.0:5760", "--connect tcpin:0.0.0.0:5760: an unsigned link open to the "
                           "network lets anyone drive the robot"),
    ("tcp:192.0.2.7:5760", "--connect tcp:192.0.2.7:5760: an unsigned link open to the "
                           "network"),
    ("serial:/dev/ttyNOPE:57600", "/dev/ttyNOPE: no such device"),
    ("tcp:127.0.0.1:FREE", "cannot connect to 127.0.0.1:FREE: Connection refused"),
])
def test_bad_refused_and_missing_links_are_one_line_at_once(
        connect: str, problem: str, capsys: Capsys) -> None:
    port = str(free_tcp_port())
    connect, problem = connect.replace("FREE", port), problem.replace("FREE", port)
    start = time.monotonic()
    code = main(["ground", "--connect", connect, "status"])
    elapsed_s = time.monotonic() - start
    assert code == 1 and problem in one_line_error(capsys)
    assert elapsed_s < 5.0  # measured: about 0.01 s
