"""Costly test files made once per test run, whichever pytest-xdist worker needs them first."""

from __future__ import annotations

import fcntl
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest


def made_once(tmp_path_factory: pytest.TempPathFactory, name: str,
              make: Callable[[Path], Any]) -> tuple[Path, Any]:
    """``make(folder)`` run once per test run, by the first of pytest-xdist's workers that
    asks (the others wait for it): a session fixture's costly files, made once instead of
    once per worker. The folder is shared by the workers: read only.

    Returns:
        The folder, and what ``make`` returned (through JSON, so the same in every worker).
    """
    if os.environ.get("PYTEST_XDIST_WORKER") is None:  # one process: nothing to share
        folder = tmp_path_factory.mktemp(name)
        return folder, json.loads(json.dumps(make(folder)))
    root = tmp_path_factory.getbasetemp().parent  # this run's, shared by its workers
    folder, made = root / name, root / f"{name}.json"
    with (root / f"{name}.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not made.exists():
            shutil.rmtree(folder, ignore_errors=True)  # a worker that failed to make it
            folder.mkdir()
            made.write_text(json.dumps(make(folder)))
    return folder, json.loads(made.read_text())
