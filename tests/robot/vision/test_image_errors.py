"""Tests of robot/vision/image_errors.py: the paper's errImageMax and errPoints."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from robot.vision.image_errors import image_errors
from shared.errors import ShapeError


class TestImageErrors:
    def test_smoke_known_answer(self) -> None:
        e = image_errors([[0.0, 0.0], [10.0, 0.0], [5.0, 5.0]],
                         [[3.0, 4.0], [10.0, 0.0], [5.0, 7.0]])
        assert e.err_image_max_px == pytest.approx(5.0)
        assert e.err_points_px == pytest.approx((5.0 + 0.0 + 2.0) / 3.0)
        assert e.n_points == 3

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError, match="pixels_key_xy"):
            image_errors(np.zeros((3, 2)), np.zeros((2, 2)))
        with pytest.raises(ShapeError, match="pixels_current_xy"):
            image_errors(np.zeros((3, 3)), np.zeros((3, 3)))

    def test_no_match_is_not_reached(self) -> None:
        e = image_errors(np.zeros((0, 2)), np.zeros((0, 2)))
        assert e.err_image_max_px == np.inf and e.err_points_px == np.inf and e.n_points == 0

    @settings(max_examples=50, deadline=None)
    @given(arrays(np.float64, st.tuples(st.integers(1, 30), st.just(2)),
                  elements=st.floats(-1e3, 1e3)),
           st.floats(-1e3, 1e3), st.floats(-1e3, 1e3))
    def test_a_common_shift_gives_its_length(self, pixels: np.ndarray, dx: float,
                                             dy: float) -> None:
        e = image_errors(pixels + np.array([dx, dy]), pixels)
        length = float(np.hypot(dx, dy))
        assert e.err_image_max_px == pytest.approx(length, abs=1e-9)
        assert e.err_points_px == pytest.approx(length, abs=1e-9)
        assert e.err_points_px <= e.err_image_max_px + 1e-12
