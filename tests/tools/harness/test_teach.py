"""Teaching short routes in the simulator with their true poses (tools/harness/teach.py), kept in
memory or stored in a folder and reused."""

from __future__ import annotations

import json
import logging
import math
import multiprocessing
import signal
from pathlib import Path

import numpy as np
import pytest

from robot.config import VmnavConfig
from shared.camera_model import CameraModel
from shared.errors import InputError
from shared.memory import read_memory
from sim.config import SimConfig
from sim.world import World, load_world
from tests.shared.memory.builders import folder_bytes
from tests.tools.short_routes import write_short_routes_world
from tools.harness.teach import TaughtMemory, teach_memory

CONFIG = VmnavConfig()
CAMERA = CameraModel.default()


@pytest.fixture(scope="module")
def world_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_short_routes_world(tmp_path_factory.mktemp("world"))


@pytest.fixture(scope="module")
def world(world_file: Path) -> World:
    return load_world(world_file)


@pytest.fixture(scope="module")
def stored(tmp_path_factory: pytest.TempPathFactory, world: World,
           world_file: Path) -> tuple[Path, TaughtMemory]:
    """``east_a`` then ``east_b`` taught, joined, into a folder, in this process (one
    CPU, as if the machine had one)."""
    folder = tmp_path_factory.mktemp("taught")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("tools.harness.teach.os.sched_getaffinity", lambda _pid: {0})
        taught = teach_memory(world, ["east_a", "east_b"], CONFIG,
                              SimConfig(world=str(world_file), seed=1), CAMERA, join=True,
                              folder=folder)
    return folder, taught


def test_one_path_per_route_and_a_true_pose_per_key_image(
        stored: tuple[Path, TaughtMemory]) -> None:
    _, taught = stored
    memory = taught.memory
    assert [memory.paths[i].name for i in taught.path_ids] == ["east_a", "east_b"]
    assert taught.true_poses.keys() == memory.keyframes.keys() and not taught.reused
    assert [r.route.name for r in taught.routes] == ["east_a", "east_b"]
    # Both run east along y = 10, east_a from x = 2 to 4.5, east_b on to 7 (the driver
    # wanders a little).
    for path_id, (x0, x1) in zip(taught.path_ids, [(2.0, 4.5), (4.5, 7.0)], strict=True):
        for key in memory.paths[path_id].keyframe_ids:
            x, y, yaw = taught.true_poses[key]
            assert x0 - 0.2 <= x <= x1 + 0.2 and abs(y - 10.0) < 0.3
            assert abs(yaw) < math.radians(30)
    assert len(memory.junctions) == 1  # joined: east_b starts where east_a ends


def test_the_folder_holds_the_memory_and_its_truth(stored: tuple[Path, TaughtMemory]) -> None:
    folder, taught = stored
    memory = read_memory(folder / "memory")
    assert memory.keyframes.keys() == taught.memory.keyframes.keys()
    assert memory.front_end == "orb, 31 px window"  # what described its points
    truth = json.loads((folder / "teach.json").read_text())
    assert truth["key"]["routes"] == ["east_a", "east_b"] and "joined" not in truth["key"]
    assert truth["path_ids"] == list(taught.path_ids)
    assert {int(k): tuple(v) for k, v in truth["true_poses"].items()} == taught.true_poses


def test_asked_again_the_same_it_is_reused_unchanged(
        stored: tuple[Path, TaughtMemory], world: World, world_file: Path) -> None:
    folder, taught = stored
    before = folder_bytes(folder)
    again = teach_memory(world, ["east_a", "east_b"], CONFIG,
                         SimConfig(world=str(world_file), seed=1), CAMERA, join=True,
                         folder=folder)
    assert again.reused and again.routes == ()
    assert again.true_poses == taught.true_poses and again.path_ids == taught.path_ids
    assert folder_bytes(folder) == before


@pytest.mark.parametrize(("routes", "seed", "join"), [
    (["east_a"], 1, True),  # other routes
    (["east_a", "east_b"], 2, True),  # another seed
    (["east_a", "east_b"], 1, False),  # not joined
])
def test_asked_otherwise_it_is_refused_and_kept(
        stored: tuple[Path, TaughtMemory], world: World, world_file: Path,
        routes: list[str], seed: int, join: bool) -> None:
    folder, _ = stored
    before = folder_bytes(folder)
    with pytest.raises(InputError, match="holds a memory taught with another world, seed"):
        teach_memory(world, routes, CONFIG, SimConfig(world=str(world_file), seed=seed), CAMERA,
                     join=join, folder=folder)
    assert folder_bytes(folder) == before


def test_unjoined_paths_in_memory_only(world: World) -> None:
    taught = teach_memory(world, ["east_a", "east_b"], CONFIG, SimConfig(seed=1), CAMERA,
                          join=False)
    assert taught.memory.junctions == () and len(taught.memory.paths) == 2


def test_routes_driven_in_parallel_give_the_memory_driven_one_after_another(
        world: World, world_file: Path, stored: tuple[Path, TaughtMemory],
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """Two CPUs: a pool of two processes drives the routes; ``stored`` drove them in
    this process."""
    monkeypatch.setattr("tools.harness.teach.os.sched_getaffinity", lambda _pid: {0, 1})
    with caplog.at_level(logging.INFO, logger="tools.harness.teach"):
        two = teach_memory(world, ["east_a", "east_b"], CONFIG,
                           SimConfig(world=str(world_file), seed=1), CAMERA, join=True)
    # Each drive's end is announced as it comes (progress of a long teach).
    announced = sorted(r.getMessage().split()[2] for r in caplog.records
                       if r.getMessage().startswith("teach: route "))
    assert announced == ["east_a", "east_b"]
    _, one = stored
    assert one.true_poses == two.true_poses and one.path_ids == two.path_ids
    assert one.memory.junctions == two.memory.junctions
    for key, record in one.memory.keyframes.items():
        assert np.array_equal(record.image, two.memory.keyframes[key].image)



def test_an_interrupted_parallel_teach_stops_its_drives(
        world: World, world_file: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C (or SIGTERM, which ``tools.cli`` turns into SystemExit) while the pool drives:
    its processes are terminated, not awaited for minutes nor left behind when the command
    is killed next."""
    monkeypatch.setattr("tools.harness.teach.os.sched_getaffinity", lambda _pid: {0, 1})
    drivers: list[multiprocessing.process.BaseProcess] = []

    def interrupt(signum: int, frame: object) -> None:
        drivers.extend(multiprocessing.active_children())
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 1.0)
        with pytest.raises(KeyboardInterrupt):
            teach_memory(world, ["east_a", "east_b"], CONFIG,
                         SimConfig(world=str(world_file), seed=1), CAMERA, join=True)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
    assert len(drivers) == 2 and multiprocessing.active_children() == []
    assert all(d.exitcode == -signal.SIGTERM for d in drivers), [d.exitcode for d in drivers]
