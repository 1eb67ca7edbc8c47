"""The lab world with two extra 2.5 m routes, so that teaching takes seconds (the tests,
``vmnav bench faults``).

``east_a`` runs along the corridor from (2, 10) to (4.5, 10); ``east_b`` carries on
from there to (7, 10), so it starts where ``east_a`` ends, facing the same way.
The landmarks are the lab's (they depend on the walls and the seed only).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from robot.config import VmnavConfig
from sim.config import SimConfig

if TYPE_CHECKING:
    from tools.harness.teach import TaughtMemory

EXTRA_ROUTES = """
[[routes]]
name = "east_a"
waypoints = [[2.0, 10.0], [4.5, 10.0]]

[[routes]]
name = "east_b"
waypoints = [[4.5, 10.0], [7.0, 10.0]]
"""


def write_short_routes_world(folder: Path) -> Path:
    """Write the lab world plus ``east_a`` and ``east_b`` to ``folder``; returns the file."""
    lab = (resources.files("sim") / "worlds" / "lab.toml").read_text()
    path = folder / "lab_short.toml"
    path.write_text(lab + EXTRA_ROUTES)
    return path


def teach_east_a(folder: Path, config: VmnavConfig) -> tuple[Path, TaughtMemory]:
    """Teach ``east_a`` in lock-step (seed 1, the default camera) into ``folder/memory``
    (:func:`tools.harness.teach.teach_memory`, its truth in ``folder/teach.json``).

    Returns:
        The world file written to ``folder`` (:func:`write_short_routes_world`), and the
        memory with the true poses of its key images.
    """
    from shared.camera_model import CameraModel
    from sim.world import load_world
    from tools.harness.teach import teach_memory

    world_file = write_short_routes_world(folder)
    taught = teach_memory(load_world(world_file), ["east_a"], config,
                          SimConfig(world=str(world_file), seed=1,
                                    camera_mount=config.camera.mount), CameraModel.default(),
                          join=False, folder=folder)
    return world_file, taught
