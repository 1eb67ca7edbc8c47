"""Stock MAVProxy in a subprocess, driven through its stdin as a person at its prompt would be.

MAVProxy reads commands from stdin when it is not a terminal and prints everything
to stdout; its ``--cmd`` option runs before the vehicle is known, so it cannot
upload a mission (reference/mavlink-vehicle.md sec. 2.1). A reader thread keeps
every line printed; :meth:`MavproxyConsole.expect` waits for a line matching a
pattern, so a test waits exactly as long as MAVProxy needs. Its exit code is
always 1, so tests grade its output and the vehicle's effects, never the code.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

#: How long MAVProxy may take to print what a command should print, s.
EXPECT_TIMEOUT_S = 15.0
#: How long MAVProxy may take to exit after ``exit``, s (then it is killed).
EXIT_TIMEOUT_S = 5.0
#: Lines of MAVProxy's output shown when an expectation fails.
TAIL_LINES = 40


class MavproxyConsole:
    """``python -m MAVProxy.mavproxy --master=<master> --no-state`` with piped stdin/stdout.

    Args:
        master: MAVProxy's ``--master`` connection string (``udpout:127.0.0.1:<port>``).
        home: an empty directory: MAVProxy's working directory and ``$HOME`` (so no
            startup script of the machine's user runs and nothing is written there).
        options: more of MAVProxy's options (``--baudrate=57600``).
    """

    def __init__(self, master: str, home: Path, *options: str) -> None:
        self.argv = [sys.executable, "-m", "MAVProxy.mavproxy", f"--master={master}",
                     "--no-state", *options]
        self.lines: list[str] = []
        """Every line MAVProxy printed so far (stdout and stderr, prompt prefixes kept)."""
        self._changed = threading.Condition()
        self._ended = False
        self._process = subprocess.Popen(
            self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True, cwd=home, env={**os.environ, "HOME": str(home), "PYTHONUNBUFFERED": "1"})
        self._reader = threading.Thread(target=self._read, name="mavproxy-stdout", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self._process.stdout is not None
        for line in self._process.stdout:
            with self._changed:
                self.lines.append(line.rstrip("\n"))
                self._changed.notify_all()
        with self._changed:
            self._ended = True
            self._changed.notify_all()

    def send(self, command: str) -> int:
        """Type ``command`` at the prompt.

        Returns:
            The index of the first line printed after it (for :meth:`expect`'s ``since``).
        """
        with self._changed:
            mark = len(self.lines)
        assert self._process.stdin is not None
        self._process.stdin.write(command + "\n")
        self._process.stdin.flush()
        return mark

    def expect(self, pattern: str, since: int = 0,
               timeout_s: float = EXPECT_TIMEOUT_S) -> re.Match[str]:
        """The first line from index ``since`` on that ``pattern`` matches (``re.search``),
        waiting for MAVProxy to print it.

        Raises:
            AssertionError: no such line within ``timeout_s``, or MAVProxy ended; the
                message holds MAVProxy's last lines.
        """
        regex = re.compile(pattern)
        deadline = time.monotonic() + timeout_s
        with self._changed:
            while True:
                for line in self.lines[since:]:
                    if match := regex.search(line):
                        return match
                since = len(self.lines)
                remaining = deadline - time.monotonic()
                if remaining <= 0 or self._ended:
                    tail = "\n".join(self.lines[-TAIL_LINES:])
                    state = "MAVProxy ended" if self._ended else f"not within {timeout_s} s"
                    raise AssertionError(f"no MAVProxy line matches {pattern!r} ({state}); "
                                         f"its last lines:\n{tail}")
                self._changed.wait(remaining)

    def lines_between(self, since: int, end_pattern: str) -> list[str]:
        """The lines from index ``since`` up to (not including) the first that
        ``end_pattern`` matches, waiting for that one (:meth:`expect`)."""
        self.expect(end_pattern, since)
        with self._changed:
            lines = self.lines[since:]
        end = next(i for i, line in enumerate(lines) if re.search(end_pattern, line))
        return lines[:end]

    def close(self) -> None:
        """Type ``exit``, wait for MAVProxy to end (kill it after ``EXIT_TIMEOUT_S``)."""
        assert self._process.stdin is not None and self._process.stdout is not None
        try:
            self._process.stdin.write("exit\n")
            self._process.stdin.close()
        except OSError:  # BrokenPipeError: MAVProxy has ended already
            pass
        try:
            self._process.wait(EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait()
        self._reader.join()
        self._process.stdout.close()


def wait_until(condition: Callable[[], bool], what: str,
               timeout_s: float = EXPECT_TIMEOUT_S) -> None:
    """Poll ``condition`` every 10 ms until it holds (for effects with no event to wait on).

    Raises:
        AssertionError: ``what`` did not happen within ``timeout_s``.
    """
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout_s} s")
        time.sleep(0.01)
