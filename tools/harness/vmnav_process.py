"""A ``vmnav`` command as a child process, its output in a file, stopped by SIGTERM.

Used by the multi-process runs that start ``vmnav robot`` (and ``vmnav sim serve``):
``vmnav demo --hil`` (:mod:`tools.harness.hil_demo`) and the fault cases' rig
(:mod:`tools.harness.hil_rig`).
"""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path


class VmnavProcess:
    """``vmnav ARGV...`` (``python -m tools.cli``) started at construction, its stdout and
    stderr in the file ``out``.

    Args:
        argv: the command and its arguments, e.g. ``["robot", "--aria", URL, ...]``.
        out: the output file (created or truncated).
        stop_grace_s: how long :meth:`stop` waits after SIGTERM before SIGKILL, s.

    Attributes:
        out: the output file.
        process: the child.
    """

    def __init__(self, argv: list[str], out: Path, stop_grace_s: float) -> None:
        self.out = out
        self._stop_grace_s = stop_grace_s
        with out.open("wb") as sink:
            self.process = subprocess.Popen([sys.executable, "-m", "tools.cli", *argv],
                                            stdout=sink, stderr=subprocess.STDOUT)

    def output(self) -> str:
        """Everything it printed so far."""
        return self.out.read_text(errors="replace")

    def last_line(self) -> str:
        """Its last line of output, for messages."""
        lines = self.output().strip().splitlines()
        return lines[-1] if lines else "no output"

    def kill(self) -> None:
        """SIGKILL, and reap it."""
        self.process.kill()
        self.process.wait()

    def stop(self) -> int:
        """SIGTERM (a clean stop) unless it has ended, SIGKILL after the grace period; its
        exit code. Again after it ended: the same code."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            return self.process.wait(self._stop_grace_s)
        except subprocess.TimeoutExpired:
            self.kill()
            return self.process.returncode
