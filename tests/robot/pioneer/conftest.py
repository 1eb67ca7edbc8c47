"""Every driver test must leave no I/O thread behind."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest


@pytest.fixture(autouse=True)
def no_leaked_io_threads() -> Iterator[None]:
    yield
    leaked = [t.name for t in threading.enumerate() if t.name == "pioneer-io"]
    assert not leaked, f"I/O threads still running: {leaked}"
