"""Ctrl-C and SIGTERM as a request to stop, for commands that run until told to.

Python turns SIGINT into a ``KeyboardInterrupt`` (and ``tools.cli`` SIGTERM into a
``SystemExit``) raised wherever the main thread happens to be. Raised between a lock's
acquire and the ``with`` block that releases it, it leaves the lock held for ever
(CPython issue 74174), and the shutdown that follows waits on it: a robot that hung
after printing its Pioneer's CLOSE. A long-running command instead asks its loop to
stop from the signal handler and unwinds from the loop, in ordinary code.

A second signal while the first is being served raises ``KeyboardInterrupt`` at once:
the way out of a shutdown that does not end.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import FrameType

#: The signals that stop a command: Ctrl-C, and a service manager's or `kill`'s stop.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def terminate_children() -> None:
    """SIGTERM every child process this process started with :mod:`multiprocessing` (a
    process pool's workers, which a signal to this process does not reach), without
    waiting for them."""
    for child in multiprocessing.active_children():
        child.terminate()


@dataclass
class StopRequest:
    """The signal that asked to stop, once one did."""

    signum: int | None = None

    @property
    def exit_status(self) -> int:
        """The shell's status for it: 128 + the signal (130 Ctrl-C, 143 SIGTERM); 0 none."""
        return 0 if self.signum is None else 128 + self.signum

    @property
    def name(self) -> str:
        """``SIGINT`` / ``SIGTERM``; empty before a signal came."""
        return "" if self.signum is None else signal.Signals(self.signum).name


@contextmanager
def stopped_by_signals(stop: Callable[[], None]) -> Iterator[StopRequest]:
    """While inside, SIGINT and SIGTERM call ``stop`` (once; a second signal raises
    ``KeyboardInterrupt``); the previous handlers are back after.

    Call from the main thread (``signal.signal``'s rule). ``stop`` runs in the signal
    handler: it must only set a flag or an event, never wait.

    Yields:
        Which signal asked to stop, filled in when one does.
    """
    request = StopRequest()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        if request.signum is not None:
            raise KeyboardInterrupt
        request.signum = signum
        stop()

    previous = {sig: signal.signal(sig, on_signal) for sig in STOP_SIGNALS}
    try:
        yield request
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
