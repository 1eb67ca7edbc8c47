"""SerialLink over real pyserial ports: open errors, reads and writes, baud alternation."""

from __future__ import annotations

import contextlib
import os
import socket
import termios
import time
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


@pytest.mark.parametrize("url", ["bogus://robot", "socket://robot"])
def test_open_failure_is_one_line_naming_the_url(url: str) -> None:
    with pytest.raises(TransportError) as info:
        SerialLink.open(url, 9600)
    message = str(info.value)
    assert message.startswith(f"{url}: cannot open at 9600 baud: ")
    assert "\n" not in message
    assert info.value.where == url


def test_a_missing_device_is_named_at_once() -> None:
    with pytest.raises(TransportError, match=r"^/dev/vmnav-no-such-port: no such device "):
        SerialLink.open("/dev/vmnav-no-such-port", 9600)


@pytest.mark.parametrize("url", ["tcp:127.0.0.1:PORT", "socket://127.0.0.1:PORT"])
def test_the_factory_connects_tcp_with_a_timeout(url: str) -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        url = url.replace("PORT", str(server.getsockname()[1]))
        link = serial_link_factory(url, 38400)()
        conn, _ = server.accept()
        with conn:
            link.write(b"\xfa\xfb")
            assert conn.recv(16) == b"\xfa\xfb"
            conn.sendall(b"back")
            deadline = time.monotonic() + 5.0
            got = b""
            while got != b"back" and time.monotonic() < deadline:
                got += link.read_available()
            assert got == b"back"
        link.close()


def test_the_factory_takes_the_rate_of_a_serial_address(pty: tuple[int, int, str]) -> None:
    _, _, path = pty
    open_next = serial_link_factory(f"serial:{path}:57600", 38400)
    rates = []
    for _ in range(3):
        link = open_next()
        assert isinstance(link, SerialLink)
        rates.append(link.baud)
        link.close()
    assert rates == [9600, 57600, 9600]


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
