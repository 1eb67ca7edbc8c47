"""Tests of robot/segment_frame.py: teach odometry, key image frames and the taught arc."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.segment_frame import (
    arc_coordinates,
    coordinates_in_next_segment,
    relative_pose,
    segment_curvature_1_m,
    wrap_angle,
)
from robot.vision.path_state import PathCoordinates
from shared.errors import DegenerateGeometryError

coordinate = st.floats(-5, 5)
angle = st.floats(-math.pi, math.pi)


def compose(a: tuple[float, float, float], b: tuple[float, float, float]) -> tuple[float, ...]:
    """Pose b (given in a's frame) in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap_angle(a[2] + b[2]))


class TestWrapAngle:
    @pytest.mark.parametrize(("angle_rad", "expected"), [
        (0.0, 0.0), (math.pi, math.pi), (-math.pi, math.pi), (3 * math.pi / 2, -math.pi / 2),
        (-7.0, -7.0 + 2 * math.pi),
    ])
    def test_known_answers(self, angle_rad: float, expected: float) -> None:
        assert wrap_angle(angle_rad) == pytest.approx(expected)

    @given(a=st.floats(-100, 100))
    def test_range(self, a: float) -> None:
        assert -math.pi < wrap_angle(a) <= math.pi
        assert math.cos(wrap_angle(a)) == pytest.approx(math.cos(a), abs=1e-9)


class TestRelativePose:
    def test_known_answer(self) -> None:
        rel = relative_pose((1.0, 2.0, math.pi / 2), (1.0, 3.0, math.pi))
        assert rel == pytest.approx((1.0, 0.0, math.pi / 2))

    @given(a=st.tuples(coordinate, coordinate, angle), b=st.tuples(coordinate, coordinate, angle))
    def test_inverts_composition(self, a: tuple[float, float, float],
                                 b: tuple[float, float, float]) -> None:
        rebuilt = compose(a, relative_pose(a, b))
        assert rebuilt[:2] == pytest.approx(b[:2], abs=1e-9)
        assert math.cos(rebuilt[2] - b[2]) == pytest.approx(1.0)


class TestSegmentCurvature:
    def test_quarter_circle(self) -> None:
        # a left quarter turn of radius 2 m: heading +90 degrees over pi m
        c = segment_curvature_1_m((0.0, 0.0, 0.0), (2.0, 2.0, math.pi / 2), math.pi)
        assert c == pytest.approx(0.5)

    def test_heading_change_is_wrapped(self) -> None:
        c = segment_curvature_1_m((0, 0, math.radians(170)), (0, 0, math.radians(-170)), 1.0)
        assert c == pytest.approx(math.radians(20))

    def test_zero_length(self) -> None:
        with pytest.raises(DegenerateGeometryError, match="segment length must be > 0"):
            segment_curvature_1_m((0, 0, 0), (0, 0, 0.1), 0.0)


class TestCoordinatesInNextSegment:
    def test_straight_route(self) -> None:
        moved = coordinates_in_next_segment(PathCoordinates(-0.1, 0.05, 0.02), (0.5, 0.0, 0.0))
        assert (moved.s_m, moved.y_m, moved.theta_rad) == pytest.approx((-0.6, 0.05, 0.02))

    def test_turning_route(self) -> None:
        # the next key image sits 1 m ahead, 1 m to the left, turned 90 degrees left
        moved = coordinates_in_next_segment(PathCoordinates(0.0, 0.0, 0.0),
                                            (1.0, 1.0, math.pi / 2))
        assert (moved.s_m, moved.y_m, moved.theta_rad) == pytest.approx(
            (-1.0, 1.0, -math.pi / 2))

    @given(robot=st.tuples(coordinate, coordinate, angle),
           key=st.tuples(coordinate, coordinate, angle))
    def test_is_the_relative_pose(self, robot: tuple[float, float, float],
                                  key: tuple[float, float, float]) -> None:
        moved = coordinates_in_next_segment(PathCoordinates(*robot), key)
        expected = relative_pose(key, robot)
        assert (moved.s_m, moved.y_m) == pytest.approx(expected[:2], abs=1e-9)
        assert math.cos(moved.theta_rad - expected[2]) == pytest.approx(1.0)


class TestArcCoordinates:
    def test_zero_curvature_is_the_line(self) -> None:
        coords = PathCoordinates(-0.3, 0.1, 0.2)
        assert arc_coordinates(coords, 0.0) == coords

    def test_point_on_the_arc(self) -> None:
        # 0.5 m of arc before the key image on a left turn of radius 2 m
        phi = -0.25
        on_arc = PathCoordinates(2 * math.sin(phi), 2 * (1 - math.cos(phi)), phi + 0.1)
        arc = arc_coordinates(on_arc, 0.5)
        assert (arc.s_m, arc.y_m, arc.theta_rad) == pytest.approx((-0.5, 0.0, 0.1), abs=1e-12)

    @given(s=st.floats(-3, 3), y=st.floats(-1, 1), theta=angle,
           c=st.one_of(st.floats(-2, -1e-6), st.floats(1e-6, 2)))
    def test_against_the_circle(self, s: float, y: float, theta: float, c: float) -> None:
        radius = 1.0 / c
        distance = math.hypot(s, y - radius)
        if distance < 1e-3:
            return
        arc = arc_coordinates(PathCoordinates(s, y, theta), c)
        # left-positive distance from the circle: towards the centre for a left turn
        assert arc.y_m == pytest.approx(math.copysign(1, c) * (abs(radius) - distance),
                                        abs=1e-9)
        # the closest point, moved along the arc by s_arc from the key image, is the
        # foot of the perpendicular from the robot
        phi = arc.s_m * c
        foot = (radius * math.sin(phi), radius * (1 - math.cos(phi)))
        assert math.hypot(s - foot[0], y - foot[1]) == pytest.approx(abs(arc.y_m), abs=1e-9)
        assert math.cos(theta - phi - arc.theta_rad) == pytest.approx(1.0)

    def test_small_curvature_is_continuous(self) -> None:
        coords = PathCoordinates(-0.4, 0.1, 0.05)
        arc = arc_coordinates(coords, 1e-12)
        assert (arc.s_m, arc.y_m, arc.theta_rad) == pytest.approx((-0.4, 0.1, 0.05), abs=1e-9)

    def test_centre_is_degenerate(self) -> None:
        with pytest.raises(DegenerateGeometryError, match="centre of the teach arc"):
            arc_coordinates(PathCoordinates(0.0, 2.0, 0.0), 0.5)
