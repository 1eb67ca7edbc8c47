"""The calibration chessboard: its inner-corner grid and the board frame.

The simulator renders boards and the calibration finds them, so both must agree
on where each corner is. Board frame: the origin is the first inner corner, x runs
along a row of inner corners, y from row to row, z = x cross y is the board's
normal; units are metres. Corners are numbered row by row, x fastest, the order in
which ``cv2.findChessboardCorners`` returns them (up to a symmetry of the grid,
which is a rigid motion of the planar board and so harmless to calibration).

A board with ``cols x rows`` inner corners has ``(cols + 1) x (rows + 1)``
squares; square ``(i, j)`` (``i = floor(x / square_m)``, ``j = floor(y / square_m)``,
from -1 to cols resp. rows) is dark when ``i + j`` is even.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.errors import check_shape


@dataclass(frozen=True, slots=True)
class Chessboard:
    """A planar chessboard calibration target.

    Attributes:
        cols: inner corners along a row (OpenCV's ``patternSize[0]``), >= 2.
        rows: inner corners along a column (``patternSize[1]``), >= 2.
        square_m: side of one square, m (> 0).
    """

    cols: int
    rows: int
    square_m: float

    def __post_init__(self) -> None:
        if self.cols < 2 or self.rows < 2:
            raise ValueError(
                f"a chessboard needs at least 2x2 inner corners, got {self.cols}x{self.rows}"
            )
        if not self.square_m > 0.0:
            raise ValueError(f"square size must be > 0 m, got {self.square_m}")

    @property
    def pattern_size(self) -> tuple[int, int]:
        """``(cols, rows)``, the ``patternSize`` argument of ``cv2.findChessboardCorners``."""
        return (self.cols, self.rows)

    @property
    def n_corners(self) -> int:
        """Number of inner corners."""
        return self.cols * self.rows

    def object_points(self) -> npt.NDArray[np.float64]:
        """Inner corners in the board frame.

        Returns:
            (cols * rows, 3) float64, m, row by row with x fastest, z = 0.
        """
        i, j = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        points = np.zeros((self.n_corners, 3))
        points[:, 0] = i.ravel() * self.square_m
        points[:, 1] = j.ravel() * self.square_m
        return points


def corner_spacing_px(board: Chessboard, corners_xy: npt.ArrayLike) -> float:
    """Smallest distance between neighbouring inner corners in an image.

    Args:
        board: the chessboard.
        corners_xy: (cols * rows, 2) corner pixels in :meth:`Chessboard.object_points`
            order, px.

    Returns:
        The smallest distance between corners adjacent along a row or a column, px.

    Raises:
        ShapeError: ``corners_xy`` is not (cols * rows, 2).
    """
    corners = np.asarray(corners_xy, dtype=np.float64)
    check_shape("corners_xy", corners.shape, (board.n_corners, 2))
    grid = corners.reshape(board.rows, board.cols, 2)
    return float(
        min(
            np.linalg.norm(np.diff(grid, axis=0), axis=2).min(),
            np.linalg.norm(np.diff(grid, axis=1), axis=2).min(),
        )
    )
