"""Route targets (junction crossings merged) and odometry increments of the route follower."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.follower import odometry_increment, targets_from_route
from robot.segment_frame import relative_pose
from shared.errors import InputError
from tests.shared.memory.builders import loop_memory


@pytest.fixture
def memory():
    return loop_memory(np.random.default_rng(4))


class TestTargetsFromRoute:
    def test_a_path_step_route_is_its_key_images(self, memory) -> None:
        assert targets_from_route(memory, [0, 1, 2]) == (0, 1, 2)

    def test_a_junction_crossing_is_one_target_on_the_continuing_path(self, memory) -> None:
        route = memory.plan_route(2, 5)
        assert route == [2, 3, 4, 5]
        assert targets_from_route(memory, route) == (2, 4, 5)

    def test_the_other_junction(self, memory) -> None:
        route = memory.plan_route(5, 1)
        assert route == [5, 6, 0, 1]
        assert targets_from_route(memory, route) == (5, 0, 1)

    def test_a_route_that_starts_on_a_junction_starts_on_the_path_it_continues(
            self, memory) -> None:
        assert targets_from_route(memory, [3, 4, 5]) == (4, 5)

    def test_an_empty_route_is_an_error(self, memory) -> None:
        with pytest.raises(InputError, match="does not connect start and goal"):
            targets_from_route(memory, [])


class TestOdometryIncrement:
    def test_straight_forward(self) -> None:
        assert odometry_increment((1.0, 2.0, 0.5), (1.0 + math.cos(0.5), 2.0 + math.sin(0.5),
                                                    0.5), 1.0) == pytest.approx((1.0, 0.0))

    def test_reversing_is_negative(self) -> None:
        ds, dpsi = odometry_increment((0.0, 0.0, 0.0), (-0.2, 0.0, 0.1), 0.2)
        assert ds == pytest.approx(-0.2) and dpsi == pytest.approx(0.1)

    @given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3), st.floats(-0.3, 0.3),
           st.floats(0.01, 0.3))
    def test_heading_change_is_the_relative_yaw(self, x, y, yaw, dpsi, ds) -> None:
        after = (x + ds * math.cos(yaw), y + ds * math.sin(yaw), yaw + dpsi)
        step, turn = odometry_increment((x, y, yaw), after, ds)
        assert step == pytest.approx(ds)
        assert turn == pytest.approx(relative_pose((x, y, yaw), after)[2], abs=1e-12)
