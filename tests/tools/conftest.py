"""A short lock-step demo shared by the demo and follow-benchmark tests (taught once)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from shared.camera_model import CameraModel
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.world import load_world
from tests.made_once import made_once
from tests.tools.short_routes import write_short_routes_world
from tools.cli import main


def render_one_frame(world_file) -> None:
    """Render a frame of the world: numba compiles the ray kernel (or loads it from its
    cache) in this process, once."""
    sim = Simulation(load_world(world_file), SimConfig(world=str(world_file)))
    FisheyeRenderer.for_simulation(sim, CameraModel.default()).render(sim)


@pytest.fixture(scope="session")
def short_demo(tmp_path_factory):
    """The lab's two short routes ``east_a`` and ``east_b`` taught (seed 1) into one memory,
    then repeated from 0.3 m / 10 degrees off ``east_a``'s start, across their junction, to
    the middle of ``east_b`` (the demo's default goal). The world file is
    ``.../lab_short.toml`` beside the output folder. Without video. Returns (exit code,
    output folder ``.../seed1``, CPU time s: of this process, every thread, teach and
    repeat, once the ray kernel is compiled; unlike the wall time, it does not grow when
    other processes take the cores; one render and one OpenCV thread, as every test
    process runs: tests/conftest.py). Read only: tests that run again on its memory copy
    ``memory`` and ``teach.json`` to a folder of their own."""
    def demo(folder: Path) -> tuple[int, float]:
        world = write_short_routes_world(folder)
        render_one_frame(world)
        started = time.process_time()
        code = main(["demo", "--world", str(world), "--routes", "east_a,east_b", "--out",
                     str(folder / "seed1"), "--no-video"])
        return code, time.process_time() - started

    folder, (code, cpu_s) = made_once(tmp_path_factory, "follow", demo)
    return code, folder / "seed1", cpu_s
