"""KeyboardTeleop: the held command, and keys from a terminal (a pty); the 10 Hz loop runs
in test_station.py."""

from __future__ import annotations

import math
import os
import pty
import termios
import time
from collections.abc import Callable

import pytest

from ground.teleop import DeadMan, KeyboardTeleop, terminal_keys


def test_keys_change_the_held_command_within_limits() -> None:
    teleop = KeyboardTeleop()
    assert all(teleop.press(key) for key in "wwwwwwwdx")  # x: ignored
    assert (teleop.x, teleop.r) == (1.0, 0.2)
    assert all(teleop.press(key) for key in "saaa")
    assert (teleop.x, teleop.r) == (0.8, -0.4)
    assert teleop.press(" ") and (teleop.x, teleop.r) == (0.0, 0.0)
    assert not teleop.press("q") and not teleop.press("\x1b")


def test_terminal_keys_reads_each_key_in_cbreak_mode_and_restores_the_terminal() -> None:
    main_fd, terminal_fd = pty.openpty()
    with os.fdopen(terminal_fd, "r") as terminal, os.fdopen(main_fd, "wb", buffering=0) as keys:
        canonical = termios.tcgetattr(terminal_fd)
        assert canonical[3] & termios.ICANON
        with terminal_keys(terminal) as read_keys:
            assert not termios.tcgetattr(terminal_fd)[3] & termios.ICANON
            assert read_keys() == ""
            keys.write(b"w")
            assert read_within(read_keys, 1) == "w"  # no Enter needed
            keys.write(b"wwd")  # typed together (key repeat): none held back
            assert read_within(read_keys, 3) == "wwd"
        assert termios.tcgetattr(terminal_fd) == canonical


def read_within(read_keys: Callable[[], str], count: int) -> str:
    """The keys read until ``count`` of them or 2 s (a pty hands them over at once, but not
    synchronously)."""
    deadline = time.monotonic() + 2.0
    keys = ""
    while len(keys) < count and time.monotonic() < deadline:
        keys += read_keys()
        time.sleep(0.01)
    return keys


def test_dead_man_holds_a_command_until_it_lapses() -> None:
    dead_man = DeadMan(timeout_ns=500)
    assert dead_man.command(0) == (0.0, 0.0)
    dead_man.hold(0.6, -0.3, 1000)
    assert dead_man.command(1500) == (0.6, -0.3)  # refreshed within the timeout
    assert dead_man.command(1501) == (0.0, 0.0)  # lapsed: released
    dead_man.hold(1.0, 1.0, 2000)
    dead_man.release()
    assert dead_man.command(2000) == (0.0, 0.0)


@pytest.mark.parametrize("x, r", [(1.01, 0.0), (0.0, -1.5), (math.nan, 0.0), (0.0, math.inf)])
def test_dead_man_refuses_axes_out_of_range(x: float, r: float) -> None:
    dead_man = DeadMan()
    dead_man.hold(0.5, 0.5, 0)
    with pytest.raises(ValueError, match=r"is not in -1\.\.1"):
        dead_man.hold(x, r, 1)
    assert dead_man.command(1) == (0.5, 0.5)  # the command held is kept
