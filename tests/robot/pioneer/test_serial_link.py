"""SerialLink over real pyserial ports: open errors, reads and writes, baud alternation."""

from __future__ import annotations

import contextlib
import os
import socket
import termios
from collections.abc import Iterator

import pytest

from robot.pioneer.serial_link import SerialLink, is_device, serial_link_factory
from shared.byte_link import ByteLink, LinkClosedError
from shared.errors import TransportError


@pytest.fixture
def pty() -> Iterator[tuple[int, int, str]]:
    master, slave = os.openpty()
    yield master, slave, os.ttyname(slave)
    for fd in (master, slave):
        with contextlib.suppress(OSError):  # the test closed it already
            os.close(fd)


def test_is_device() -> None:
    assert is_device("/dev/ttyUSB0") and is_device("/dev/pts/3")
    assert not is_device("socket://127.0.0.1:8101") and not is_device("loop://")


@pytest.mark.parametrize("url", ["/dev/vmnav-no-such-port", "bogus://robot", "socket://robot"])
def test_open_failure_is_one_line_naming_the_url(url: str) -> None:
    with pytest.raises(TransportError) as info:
        SerialLink.open(url, 9600)
    message = str(info.value)
    assert message.startswith(f"{url}: cannot open at 9600 baud: ")
    assert "\n" not in message
    assert info.value.where == url


def test_refused_tcp_connection() -> None:
    with socket.socket() as bound:  # bound but not listening: the connect is refused
        bound.bind(("127.0.0.1", 0))
        url = f"socket://127.0.0.1:{bound.getsockname()[1]}"
        with pytest.raises(TransportError, match="refused"):
            SerialLink.open(url)


def test_loop_round_trip_and_close() -> None:
    link = SerialLink.open("loop://", 38400)
    assert isinstance(link, ByteLink)
    assert link.read_available() == b""
    link.write(b"\xfa\xfb\x03\x00\x00\x00")
    assert link.read_available() == b"\xfa\xfb\x03\x00\x00\x00"
    link.close()
    link.close()
    with pytest.raises(LinkClosedError, match=r"^loop://: read failed"):
        link.read_available()
    with pytest.raises(LinkClosedError, match=r"^loop://: write failed"):
        link.write(b"x")


def test_pty_both_ways_and_hangup(pty: tuple[int, int, str]) -> None:
    master, slave, path = pty
    link = SerialLink.open(path)
    link.write(b"SYNC")
    assert os.read(master, 100) == b"SYNC"
    os.write(master, b"\xfa\xfb")
    assert link.read_available() == b"\xfa\xfb"
    os.close(slave)
    os.close(master)  # the robot end is gone
    with pytest.raises(LinkClosedError, match=f"^{path}: read failed"):
        link.read_available()
    link.close()


def test_factory_alternates_9600_and_the_configured_rate_on_a_device(
        pty: tuple[int, int, str]) -> None:
    _, slave, path = pty
    open_next = serial_link_factory(path, 38400)
    rates = []
    for expected in (termios.B9600, termios.B38400, termios.B9600):
        link = open_next()
        rates.append(link.baud)
        assert termios.tcgetattr(slave)[4] == expected  # the port's input speed
        link.close()
    assert rates == [9600, 38400, 9600]
    same = serial_link_factory(path, 9600)
    assert [same().baud for _ in range(2)] == [9600, 9600]


def test_factory_keeps_the_rate_on_urls() -> None:
    open_next = serial_link_factory("loop://", 115200)
    assert [open_next().baud for _ in range(3)] == [115200] * 3
