"""The driver end to end over real transports, with its I/O thread: a pty and TCP."""

from __future__ import annotations

import math
import os
import socket

import pytest

from robot.config import PioneerDriverConfig
from robot.pioneer.driver import PioneerDriver
from robot.pioneer.events import LinkLost
from robot.pioneer.serial_link import serial_link_factory
from shared.aria.commands import ClientCommand, Command
from shared.clock import WallClock
from tests.robot.pioneer.real_links import FdLink, SocketLink, serve_until
from tests.robot.pioneer.responder import MS, Responder

S = 1_000_000_000


def received(robot: Responder, command: ClientCommand) -> bool:
    return command in [e for _, e in robot.received]


def drive_and_check(driver: PioneerDriver, robot: Responder) -> None:
    """Connected driver: a command reaches the robot, the robot's motion reaches odometry."""
    driver.command(0.2, math.radians(10))
    serve_until(robot, lambda: received(robot, ClientCommand(Command.VEL, 200)))
    assert received(robot, ClientCommand(Command.RVEL, 10))
    robot.x_counts += 200
    serve_until(robot, lambda: driver.state().odom_pose[0] > 0)
    assert driver.state().odom_pose == pytest.approx((0.2, 0.0, 0.0))


def test_driver_over_a_pty() -> None:
    master, slave = os.openpty()  # the test keeps the slave open: no EIO between opens
    robot = Responder()
    robot.link = FdLink(master)
    driver = PioneerDriver(serial_link_factory(os.ttyname(slave), 38400), WallClock())
    try:
        driver.start_thread()
        serve_until(robot, lambda: driver.status().motors_enabled)
        drive_and_check(driver, robot)
    finally:
        driver.close()
        robot.service(WallClock().now_ns())
        os.close(master)
        os.close(slave)
    assert received(robot, ClientCommand(Command.CLOSE, 1))
    assert driver.counters().connects == 1


def test_driver_over_tcp_reconnects_when_the_robot_drops_the_socket() -> None:
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(5.0)
    port = server.getsockname()[1]
    config = PioneerDriverConfig(url=f"socket://127.0.0.1:{port}", reconnect_initial_ns=50 * MS)
    driver = PioneerDriver.from_config(config, WallClock())
    robot = Responder()
    try:
        driver.start_thread()
        robot.link = SocketLink(server.accept()[0])
        serve_until(robot, lambda: driver.wait_connected(1 * MS))
        drive_and_check(driver, robot)
        robot.link.close()  # a TCP robot ends the connection; the driver's read fails
        robot.link = None
        robot.reboot()
        robot.link = SocketLink(server.accept()[0])
        serve_until(robot, lambda: driver.status().motors_enabled)
        assert driver.state().odom_pose == pytest.approx((0.2, 0.0, 0.0))
        assert any(isinstance(e, LinkLost) for e in iter(driver.next_event, None))
    finally:
        driver.close()
        server.close()
    serve_until(robot, lambda: robot.link is None)  # read to the end of the stream
    assert received(robot, ClientCommand(Command.CLOSE, 1))
    assert driver.counters().connects == 2


def test_wait_connected_with_the_thread_times_out_without_a_robot() -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    driver = PioneerDriver(serial_link_factory(f"socket://127.0.0.1:{port}", 9600), WallClock())
    try:
        driver.start_thread()
        assert not driver.wait_connected(100 * MS)
    finally:
        driver.close()
        server.close()
    assert not driver.wait_connected(S)  # closed: returns at once
