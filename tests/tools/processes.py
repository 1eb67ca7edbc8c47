"""vmnav commands as child processes for the multi-process tests: start, and wait for output."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

VMNAV = [sys.executable, "-m", "tools.cli"]


def start(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
    """``vmnav ARGV...`` with stdout and stderr into the file ``log``."""
    return subprocess.Popen([*VMNAV, *argv], stdout=log.open("wb"), stderr=subprocess.STDOUT)


def wait_for(pattern: str, log: Path, process: subprocess.Popen[bytes],
             timeout_s: float = 30.0) -> re.Match[str]:
    """The first match of ``pattern`` in the process's output, waiting for it."""
    limit = time.monotonic() + timeout_s
    while time.monotonic() < limit:
        found = re.search(pattern, log.read_text())
        if found:
            return found
        assert process.poll() is None, log.read_text()
        time.sleep(0.1)
    raise AssertionError(f"no {pattern!r} in: {log.read_text()}")
