"""The lab world with two extra 2.5 m routes, so that teaching takes seconds (the tests,
``vmnav bench faults``).

``east_a`` runs along the corridor from (2, 10) to (4.5, 10); ``east_b`` carries on
from there to (7, 10), so it starts where ``east_a`` ends, facing the same way.
The landmarks are the lab's (they depend on the walls and the seed only).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from robot.config import VmnavConfig
from sim.config import SimConfig

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


def teach_east_a(folder: Path, config: VmnavConfig) -> Path:
    """Teach ``east_a`` in lock-step (seed 1, the default camera) into ``folder/memory``.

    Returns:
        The world file written to ``folder`` (:func:`write_short_routes_world`).
    """
    from shared.calibration import load_camera
    from shared.memory import VisualMemory, write_memory
    from sim.world import load_world
    from tools.harness.teach import find_route, teach_in_sim

    world_file = write_short_routes_world(folder)
    world = load_world(world_file)
    camera = load_camera(None)
    route = find_route(world, "east_a")
    sim_config = SimConfig(world=str(world_file), seed=1, camera_mount=config.camera.mount)
    taught = teach_in_sim(world, route, config, sim_config, camera)
    memory = VisualMemory(camera)
    memory.add_path(route.name, [k.record for k in taught.key_images])
    write_memory(folder / "memory", memory)
    return world_file
