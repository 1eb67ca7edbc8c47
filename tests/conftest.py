"""Fixtures shared by every test package."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest

from shared.clock import ManualClock
from tests.made_once import made_once
from tools.threads import compute_threads, one_blas_thread

if TYPE_CHECKING:
    from tools.harness.hil_rig import Taught

one_blas_thread()  # as every vmnav command runs (tools/__init__.py)
compute_threads(1)  # `make test` runs a worker per CPU: threads that wait would burn CPU


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: tests are deterministic."""
    return np.random.default_rng(20081215)


@pytest.fixture
def manual_clock() -> ManualClock:
    """A clock that starts at 0 ns and moves only when told."""
    return ManualClock()


@pytest.fixture(scope="session")
def east_a(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(world file, memory folder): the lab's 2.5 m ``east_a`` route taught once per test
    run in lock-step (seed 1; tools/harness/short_routes.py), with the default config.
    Read only: copy the memory before changing it."""
    from robot.config import VmnavConfig
    from tools.harness.short_routes import teach_east_a

    def teach(folder: Path) -> str:
        world_file, _ = teach_east_a(folder, VmnavConfig())
        return str(world_file)

    folder, world_file = made_once(tmp_path_factory, "east_a", teach)
    return Path(world_file), folder / "memory"


@pytest.fixture(scope="session")
def east_a_taught(east_a: tuple[Path, Path]) -> Taught:
    """``east_a`` (above) with the true poses of its key images, as the hardware-in-the-loop
    rig takes it (its cases work on copies of the memory). Read only."""
    from shared.memory import read_memory
    from tools.harness.hil_rig import Taught
    from tools.harness.teach import TRUTH_NAME, taught_from_truth

    world_file, memory_dir = east_a
    truth = json.loads((memory_dir.parent / TRUTH_NAME).read_text())
    return Taught(world_file, memory_dir, taught_from_truth(read_memory(memory_dir), truth))
