"""Tests of shared/chessboard.py: the board's corner grid."""

from __future__ import annotations

import numpy as np
import pytest

from shared.chessboard import Chessboard, corner_spacing_px
from shared.errors import ShapeError


class TestChessboard:
    def test_object_points(self) -> None:
        board = Chessboard(cols=3, rows=2, square_m=0.5)
        assert board.pattern_size == (3, 2) and board.n_corners == 6
        np.testing.assert_array_equal(
            board.object_points(),
            [[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [0, 0.5, 0], [0.5, 0.5, 0], [1, 0.5, 0]],
        )

    @pytest.mark.parametrize(
        ("cols", "rows", "square_m"), [(1, 6, 0.025), (9, 1, 0.025), (9, 6, 0.0), (9, 6, -1.0)]
    )
    def test_invalid_boards(self, cols: int, rows: int, square_m: float) -> None:
        with pytest.raises(ValueError, match=r"chessboard|square"):
            Chessboard(cols, rows, square_m)


class TestCornerSpacing:
    def test_known_answer(self) -> None:
        board = Chessboard(cols=3, rows=2, square_m=0.5)
        # Columns 10 px apart, rows 4 px apart (a board squeezed vertically).
        corners = board.object_points()[:, :2] * [20.0, 8.0] + [100.0, 50.0]
        assert corner_spacing_px(board, corners) == pytest.approx(4.0)

    def test_shape_error(self) -> None:
        with pytest.raises(ShapeError, match="corners_xy"):
            corner_spacing_px(Chessboard(3, 2, 0.5), np.zeros((5, 2)))
