"""A short lock-step demo shared by the demo and follow-benchmark tests (taught once)."""

from __future__ import annotations

import time

import pytest

from tools.cli import main


@pytest.fixture(scope="session")
def short_demo(tmp_path_factory):
    """The corridor taught (seed 1), then repeated from 0.3 m / 10 degrees off to its key
    image 12. Returns (exit code, output folder ``.../seed1``, CPU time s: of this process,
    every thread, teach and repeat; unlike the wall time, it does not grow when other
    processes take the cores)."""
    out = tmp_path_factory.mktemp("follow") / "seed1"
    started = time.process_time()
    code = main(["demo", "--routes", "corridor", "--goal", "12", "--out", str(out),
                 "--no-video"])
    return code, out, time.process_time() - started
