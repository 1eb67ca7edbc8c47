"""Fixtures shared by every test package."""

from __future__ import annotations

import numpy as np
import pytest

from shared.clock import ManualClock
from tools.threads import one_blas_thread

one_blas_thread()  # as every vmnav command runs (tools/__init__.py)


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: tests are deterministic."""
    return np.random.default_rng(20081215)


@pytest.fixture
def manual_clock() -> ManualClock:
    """A clock that starts at 0 ns and moves only when told."""
    return ManualClock()
