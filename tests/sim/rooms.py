"""Tiny worlds for the simulator's tests."""

from __future__ import annotations

from shared.pose import Pose2
from sim.world import LandmarkDensity, Wall, World


def box_room(
    size: tuple[float, float] = (10.0, 6.0),
    start: Pose2 | None = None,
    density: LandmarkDensity | None = None,
) -> World:
    """A bare rectangular room, walls 2.5 m high along x = 0, x = size[0], y = 0, y = size[1].

    Args:
        size: (width along x, depth along y), m.
        start: the start pose; None = the room's centre, facing +x.
        density: landmark densities; None = the defaults.
    """
    w, h = size
    corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
    walls = tuple(Wall(a, b, 2.5) for a, b in zip(corners, corners[1:] + corners[:1], strict=True))
    return World(
        name="room",
        walls=walls,
        start=start or Pose2(w / 2, h / 2, 0.0),
        landmarks=density or LandmarkDensity(),
    )
