"""The lab world with two extra 2.5 m routes, so that teaching in tests takes seconds.

``east_a`` runs along the corridor from (2, 10) to (4.5, 10); ``east_b`` carries on
from there to (7, 10), so it starts where ``east_a`` ends, facing the same way.
The landmarks are the lab's (they depend on the walls and the seed only).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

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
