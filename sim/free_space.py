"""Where one can stand in a world: a floor-plan raster of the space reachable from the start.

Walls (with their thickness) and furniture footprints are drawn into an occupancy
grid; a flood fill from the start pose marks the free cells a walker could reach.
Cells cut off by walls (the inside of a building block, a room without a door)
are not reachable. The landmark field uses it to put patches only on surfaces
that face reachable space, the people use it to pick places to walk to, and the
world checks use it to refuse routes that cannot be driven from the start.

Resolution: 5 cm cells by default; the reachable set is exact to about one cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import cv2
import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from sim.world import World

WALL_HALF_THICKNESS_M = 0.05
"""Walls are 10 cm thick, centred on their segment (the pymunk segment radius)."""

_MARGIN_M = 0.5  # free border around the walls' bounding box


@dataclass(frozen=True, eq=False)
class FreeSpaceMap:
    """Occupancy raster of a world, and the part of it reachable from the start.

    Cell ``[row, col]`` covers x in ``[x0 + col*res, x0 + (col+1)*res)``, y likewise
    with rows (row 0 at the smallest y).

    Attributes:
        origin_xy: (x0, y0) world coordinates of the grid's corner, m.
        resolution_m: cell side, m.
        reachable: (H, W) bool, free and connected to the start position.
        clearance_m: (H, W) float32, distance from the cell centre to the nearest
            wall or furniture, m (0 inside them).
    """

    origin_xy: tuple[float, float]
    resolution_m: float
    reachable: npt.NDArray[np.bool_]
    clearance_m: npt.NDArray[np.float32]
    _cells_with_clearance: dict[float, npt.NDArray[np.intp]] = field(
        default_factory=dict, init=False, repr=False
    )

    @classmethod
    def from_world(cls, world: World, resolution_m: float = 0.05) -> FreeSpaceMap:
        """Rasterize ``world`` and flood-fill from ``world.start``.

        Raises:
            ValueError: the start position is not in free space.
        """
        ends = np.array([w.start for w in world.walls] + [w.end for w in world.walls], dtype=float)
        x0, y0 = ends.min(axis=0) - _MARGIN_M
        x1, y1 = ends.max(axis=0) + _MARGIN_M
        width = math.ceil((x1 - x0) / resolution_m)
        height = math.ceil((y1 - y0) / resolution_m)
        occupied = np.zeros((height, width), np.uint8)
        # Sub-pixel drawing: coordinates in 1/16 px (shift=4).
        scale = 16.0 / resolution_m

        def px(xy: tuple[float, float] | npt.NDArray[np.float64]) -> tuple[int, int]:
            return round((xy[0] - x0) * scale - 8), round((xy[1] - y0) * scale - 8)

        # One extra cell of thickness so that diagonal walls cannot leak.
        thickness = max(2, math.ceil(2 * WALL_HALF_THICKNESS_M / resolution_m) + 1)
        for wall in world.walls:
            cv2.line(occupied, px(wall.start), px(wall.end), 1, thickness, cv2.LINE_8, 4)
        boxes = np.concatenate([world.furniture_corners(), world.object_corners()])
        for box in boxes:
            cv2.fillConvexPoly(occupied, np.array([px(c) for c in box], np.int32), 1,
                               cv2.LINE_8, 4)
        for tree in world.trees:
            cv2.circle(occupied, px(tree.at), round(tree.trunk_radius_m * scale), 1,
                       cv2.FILLED, cv2.LINE_8, 4)
        free = (occupied == 0).astype(np.uint8)
        clearance = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * resolution_m
        col = int((world.start.x_m - x0) / resolution_m)
        row = int((world.start.y_m - y0) / resolution_m)
        if not (0 <= row < height and 0 <= col < width) or not free[row, col]:
            raise ValueError(f"start ({world.start.x_m}, {world.start.y_m}) is not in free space")
        mask = np.zeros((height + 2, width + 2), np.uint8)
        cv2.floodFill(free, mask, (col, row), 2, flags=4)
        return cls((float(x0), float(y0)), resolution_m, free == 2, clearance.astype(np.float32))

    def _cells(
        self, points_xy: npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp], npt.NDArray[np.bool_]]:
        cols = np.floor((points_xy[:, 0] - self.origin_xy[0]) / self.resolution_m).astype(np.intp)
        rows = np.floor((points_xy[:, 1] - self.origin_xy[1]) / self.resolution_m).astype(np.intp)
        inside = (
            (rows >= 0)
            & (rows < self.reachable.shape[0])
            & (cols >= 0)
            & (cols < self.reachable.shape[1])
        )
        return np.where(inside, rows, 0), np.where(inside, cols, 0), inside

    def is_reachable(self, points_xy: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:
        """Whether each point lies in a reachable free cell.

        Args:
            points_xy: (N, 2) world positions, m.

        Returns:
            (N,) bool; False outside the map.
        """
        rows, cols, inside = self._cells(points_xy)
        return inside & self.reachable[rows, cols]

    def clearance_at(self, points_xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float32]:
        """Distance to the nearest wall or furniture at each point's cell, m (0 outside the map).

        Args:
            points_xy: (N, 2) world positions, m.

        Returns:
            (N,) float32; exact to about one cell.
        """
        rows, cols, inside = self._cells(points_xy)
        return np.where(inside, self.clearance_m[rows, cols], np.float32(0.0))

    def path_is_clear(
        self, start_xy: tuple[float, float], end_xy: tuple[float, float], min_clearance_m: float
    ) -> bool:
        """Whether a disc can slide from start to end keeping ``min_clearance_m`` from obstacles.

        Samples the straight path every half cell against the clearance raster and
        the reachable set. (A thick pymunk segment query is not used: its
        bounding-box pre-filter uses the thin segment and misses wall ends that
        only the thick one would touch.)
        """
        a, b = np.asarray(start_xy, dtype=float), np.asarray(end_xy, dtype=float)
        count = max(2, math.ceil(2 * float(np.linalg.norm(b - a)) / self.resolution_m) + 1)
        points = a + np.linspace(0.0, 1.0, count)[:, None] * (b - a)
        return bool(
            np.all(self.clearance_at(points) >= min_clearance_m)
            and np.all(self.is_reachable(points))
        )

    def sample_points(
        self, rng: np.random.Generator, count: int, min_clearance_m: float
    ) -> npt.NDArray[np.float64]:
        """Draw points uniformly over the reachable cells at least ``min_clearance_m`` clear.

        Args:
            rng: the random generator.
            count: number of points.
            min_clearance_m: smallest distance to walls and furniture, m.

        Returns:
            (count, 2) world positions, m.

        Raises:
            ValueError: no reachable cell has that much clearance.
        """
        cells = self._cells_with_clearance.get(min_clearance_m)
        if cells is None:
            rows, cols = np.nonzero(
                self.reachable & (self.clearance_m >= min_clearance_m + self.resolution_m)
            )
            cells = self._cells_with_clearance[min_clearance_m] = np.stack([cols, rows], axis=1)
        if len(cells) == 0:
            raise ValueError(
                f"no reachable place is {min_clearance_m} m clear of walls and furniture"
            )
        pick = rng.integers(0, len(cells), count)
        jitter = rng.uniform(0.0, 1.0, (count, 2))
        return (cells[pick] + jitter) * self.resolution_m + np.asarray(self.origin_xy)
