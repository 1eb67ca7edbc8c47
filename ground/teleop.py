"""Keyboard teleoperation: keys to MANUAL_CONTROL axes, and the 10 Hz loop that sends them.

Keys (teleop_twist_keyboard's habit: a key changes the command, the command holds):

=========  ===========================================================
``w``/``s``  forward axis ``x`` up/down by :data:`STEP` (-1..1)
``a``/``d``  yaw axis ``r`` left/right by :data:`STEP` (-1..1; MAVLink
             yaw is clockwise positive, so ``a`` lowers it)
space       stop: both axes 0
``q``, Esc  quit (a last all-zero MANUAL_CONTROL goes out, also on Ctrl-C)
=========  ===========================================================

The robot stops by itself when MANUAL_CONTROL stops coming (its dead-man timer), so
the loop sends the held command every period, changed or not.

A remote operator (the web app's keyboard and gamepad, ``ground.web``) holds a stick
instead: :class:`DeadMan` keeps the axes it last sent and lapses to zero when they are
not refreshed within :data:`DEADMAN_NS` (a released key or stick, a page gone away).

:func:`drive_in_terminal` reads the keys from a terminal, put in cbreak mode (each key
as typed, no Enter needed) for the drive and restored after it.
"""

from __future__ import annotations

import contextlib
import os
import select
import termios
import tty
from collections.abc import Callable, Iterator
from typing import TextIO

from ground.station import GroundStation
from shared.clock import Clock

#: Change of an axis per key press (axes run -1..1).
STEP = 0.2
#: MANUAL_CONTROL period, ns (10 Hz).
PERIOD_NS = 100_000_000
#: A remote stick command not refreshed for this long counts as released, ns (the web
#: app refreshes it at 10 Hz; a busy browser may skip a few).
DEADMAN_NS = 500_000_000
#: The keys, for people.
KEYS_HELP = "w/s speed, a/d turn, space stop, q quit"
_QUIT = frozenset("q\x1b")


class KeyboardTeleop:
    """The held command (module docstring): ``x`` forward, ``r`` yaw clockwise, -1..1."""

    def __init__(self) -> None:
        self.x = 0.0
        self.r = 0.0

    def press(self, key: str) -> bool:
        """Apply one key; unknown keys are ignored.

        Returns:
            False when the key asks to quit.
        """
        if key in _QUIT:
            return False
        steps = {"w": (STEP, 0.0), "s": (-STEP, 0.0), "a": (0.0, -STEP), "d": (0.0, STEP)}
        if key == " ":
            self.x = self.r = 0.0
        elif key in steps:
            dx, dr = steps[key]
            self.x = round(min(1.0, max(-1.0, self.x + dx)), 6)
            self.r = round(min(1.0, max(-1.0, self.r + dr)), 6)
        return True


class DeadMan:
    """A remote operator's held stick, which lapses to zero unless refreshed (pure; module
    docstring).

    Args:
        timeout_ns: how long a command holds without a refresh, ns.
    """

    def __init__(self, timeout_ns: int = DEADMAN_NS) -> None:
        self.timeout_ns = timeout_ns
        self._x = 0.0
        self._r = 0.0
        self._held_ns: int | None = None

    def hold(self, x: float, r: float, now_ns: int) -> None:
        """Hold ``x`` forward and ``r`` yaw (clockwise), each -1..1, from ``now_ns``.

        Raises:
            ValueError: an axis that is not a number in -1..1.
        """
        for name, value in (("x", x), ("r", r)):
            if not -1.0 <= value <= 1.0:  # False for NaN too
                raise ValueError(f"{name} {value!r} is not in -1..1")
        self._x, self._r, self._held_ns = float(x), float(r), now_ns

    def release(self) -> None:
        """Both axes 0 now."""
        self._x = self._r = 0.0
        self._held_ns = None

    def command(self, now_ns: int) -> tuple[float, float]:
        """``(x, r)`` to send at ``now_ns``: the held command, or zeros once it lapsed."""
        if self._held_ns is None or now_ns - self._held_ns > self.timeout_ns:
            return 0.0, 0.0
        return self._x, self._r


def drive(station: GroundStation, read_keys: Callable[[], str], clock: Clock,
          show: Callable[[KeyboardTeleop], None] = lambda teleop: None,
          period_ns: int = PERIOD_NS) -> None:
    """Send the held command every ``period_ns`` until a quit key; then one all-zero one.

    Args:
        station: a station talking to a vehicle (``wait_vehicle`` done).
        read_keys: the keys pressed since the last call, without blocking ("" if none).
        clock: paces the loop.
        show: called once keys are read (the command held, zero: the operator may type)
            and after each key but a quit key, e.g. to print the held command.
        period_ns: MANUAL_CONTROL period, ns.
    """
    teleop = KeyboardTeleop()
    show(teleop)
    deadline_ns = clock.now_ns()
    try:
        while True:
            for key in read_keys():
                if not teleop.press(key):
                    return
                show(teleop)
            station.send_manual_control(teleop.x, teleop.r)
            deadline_ns += period_ns
            station.run_until(lambda: False, max(0, deadline_ns - clock.now_ns()))
    finally:
        station.send_manual_control(0.0, 0.0)


@contextlib.contextmanager
def terminal_keys(terminal: TextIO) -> Iterator[Callable[[], str]]:
    """Put ``terminal`` in cbreak mode until exit; yields its ``read_keys`` for :func:`drive`.

    Raises:
        termios.error: ``terminal`` is not a terminal.
    """
    fd = terminal.fileno()

    def read_keys() -> str:
        # From the descriptor, not ``terminal.read``: the text layer would buffer keys
        # typed together (key repeat) where ``select`` no longer sees them. Keys are ASCII;
        # anything else becomes U+FFFD, an unknown key.
        keys = ""
        while select.select([fd], [], [], 0)[0]:
            keys += os.read(fd, 64).decode("ascii", errors="replace")
        return keys

    saved = termios.tcgetattr(fd)
    tty.setcbreak(fd)
    try:
        yield read_keys
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def drive_in_terminal(station: GroundStation, terminal: TextIO, out: TextIO) -> None:
    """:func:`drive` from the keys typed in ``terminal``, after a line of help on ``out``;
    the held command is shown on one line of ``out``, rewritten after each key.

    Raises:
        termios.error: ``terminal`` is not a terminal.
    """

    def show(teleop: KeyboardTeleop) -> None:
        print(f"\rforward {teleop.x:+.1f}  yaw {teleop.r:+.1f}   ", end="", file=out, flush=True)

    print(KEYS_HELP, file=out)
    try:
        with terminal_keys(terminal) as read_keys:
            drive(station, read_keys, station.clock, show)
    finally:
        print(file=out)
