"""Route targets (junction crossings merged) and odometry increments of the route follower."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.config import VmnavConfig
from robot.follower import (
    _PARTNERS,
    _SHORT_BASELINE_M,
    FollowerConfig,
    InitGate,
    RouteFollower,
    _partners,
    chain_tracks,
    odometry_increment,
    targets_from_route,
)
from robot.segment_frame import relative_pose
from robot.vision.features import pixels_per_radian
from robot.vision.frame_state import FrameState
from robot.vision.image_errors import ImageErrors
from robot.vision.path_state import PathState
from shared.interfaces import BaseState
from tests.shared.memory.builders import loop_memory


@pytest.fixture
def memory():
    return loop_memory(np.random.default_rng(4))


class TestPartners:
    def test_earlier_key_images_first_then_later_ones_with_chained_tracks(self, memory) -> None:
        path = memory.paths[0].keyframe_ids  # 4 key images; _PARTNERS is 3
        key = memory.keyframe(path[1])
        found = list(_partners(memory, key))
        assert [p.id for p, _ in found] == [path[0], path[2], path[3]]
        # The nearest of each side: the teach tracks themselves, as (key's, partner's).
        after = memory.keyframe(path[2])

        def rows(tracks: np.ndarray) -> list[tuple[int, int]]:
            return sorted(map(tuple, tracks.tolist()))

        assert rows(found[0][1]) == rows(key.tracked_from_previous[:, ::-1])
        assert rows(found[1][1]) == rows(after.tracked_from_previous)
        # Further on: chained through the key image between.
        assert rows(found[2][1]) == rows(chain_tracks(
            after.tracked_from_previous, memory.keyframe(path[3]).tracked_from_previous))

    def test_the_first_key_image_pairs_forward_only(self, memory) -> None:
        path = memory.paths[0].keyframe_ids
        assert [p.id for p, _ in _partners(memory, memory.keyframe(path[0]))] == list(
            path[1:_PARTNERS + 1])


def test_a_key_image_pairs_past_a_neighbour_closer_than_the_short_baseline(east_a) -> None:
    """In ``east_a`` the second key image was taught 14.5 cm after the first: it pairs
    with the one after it instead, the nearest at least :data:`_SHORT_BASELINE_M` away."""
    from shared.memory import read_memory

    memory = read_memory(east_a[1])
    (path,) = memory.paths.values()
    ids = path.keyframe_ids
    distance = [memory.keyframes[k].distance_m for k in ids]
    assert distance[1] - distance[0] < _SHORT_BASELINE_M <= distance[2] - distance[1]
    config = VmnavConfig()
    follower = RouteFollower(memory, list(ids), FollowerConfig(
        features=config.features, path_state=config.path_state, estimator=config.estimator,
        switching=config.switching, control=config.control, mount=config.camera.mount),
        np.random.default_rng(0), 0, BASE)
    segment = follower._segment(1)
    assert segment is not None
    assert segment.key_pair.baseline_m == pytest.approx(distance[2] - distance[1], abs=0.02)


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
        with pytest.raises(ValueError, match="does not connect start and goal"):
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


class TestChainTracks:
    def test_composes_through_the_shared_middle_image_in_the_first_lists_order(self) -> None:
        a_b = [[0, 5], [1, 7], [2, 9]]
        b_c = [[9, 30], [5, 10], [8, 40]]
        assert chain_tracks(a_b, b_c).tolist() == [[0, 10], [2, 30]]

    def test_nothing_shared_gives_an_empty_list(self) -> None:
        chained = chain_tracks([[0, 1]], np.zeros((0, 2), dtype=np.int64))
        assert chained.shape == (0, 2) and chained.dtype == np.int64


BASE = BaseState(odom_pose=(0.0, 0.0, 0.0), odom_distance_m=0.0, bumped=False, stalled=False,
                 battery_v=13.0, motors_enabled=True)


def make_follower(memory) -> RouteFollower:
    config = VmnavConfig()
    follower_config = FollowerConfig(  # loop_memory stores the paper's ZNCC patches
        features=dataclasses.replace(
            config.features, method="harris-zncc",
            patch_size_deg=math.degrees(5.0 / pixels_per_radian(memory.camera))),
        path_state=config.path_state,
        estimator=config.estimator, switching=config.switching, control=config.control,
        mount=config.camera.mount)
    route = memory.paths[0].keyframe_ids[:3]
    return RouteFollower(memory, list(route), follower_config, np.random.default_rng(0), 0, BASE)


def blank(memory) -> np.ndarray:
    return np.full((memory.camera.height, memory.camera.width), 128, dtype=np.uint8)


def vision_with(n_points: int, y_m: float) -> FrameState:
    state = PathState(y_m=y_m, theta_rad=0.0, s_m=-0.3, ok=True, scale_source="three-view",
                      n_inliers=40, n_points=n_points)
    return FrameState(state=state, image_errors=ImageErrors(30.0, 20.0, 40), matches=40)


class TestNoEstimate:
    def test_the_robot_stands_still_until_its_first_estimate(self, memory) -> None:
        follower = make_follower(memory)
        step = follower.step(66_000_000, blank(memory), BASE)
        assert step.y_m is None
        assert (step.twist.v_m_s, step.twist.omega_rad_s) == (0.0, 0.0)

    def test_only_an_estimate_on_enough_points_starts_the_filter(self, memory,
                                                                 monkeypatch) -> None:
        follower = make_follower(memory)
        monkeypatch.setattr(follower, "_vision", lambda index, corners: vision_with(3, 1.05))
        assert follower.step(66_000_000, blank(memory), BASE).y_m is None
        monkeypatch.setattr(follower, "_vision", lambda index, corners: vision_with(12, 0.05))
        step = follower.step(133_000_000, blank(memory), BASE)
        assert step.y_m == pytest.approx(0.05)
        assert step.twist.v_m_s > 0


class TestInitGate:
    CONFIG = VmnavConfig().estimator  # 10 points, or 5 agreeing over 3 frames

    def test_enough_points_initialise_at_once(self) -> None:
        assert InitGate(self.CONFIG).admits(0, 0.3, 0.17, n_points=10)

    def test_fewer_points_initialise_when_three_frames_in_a_row_agree(self) -> None:
        gate = InitGate(self.CONFIG)
        assert not gate.admits(0, 0.30, 0.170, n_points=6)
        assert not gate.admits(0, 0.31, 0.175, n_points=5)
        assert gate.admits(0, 0.29, 0.165, n_points=7)

    @pytest.mark.parametrize("odd", [
        (0, 0.40, 0.17, 6),  # y 10 cm off
        (0, 0.30, 0.25, 6),  # theta 4.6 deg off
        (1, 0.30, 0.17, 6),  # another target
    ])
    def test_a_frame_that_disagrees_starts_the_count_again(self, odd) -> None:
        gate = InitGate(self.CONFIG)
        assert not gate.admits(0, 0.30, 0.17, n_points=6)
        index, y, theta, points = odd
        assert not gate.admits(index, y, theta, n_points=points)
        assert not gate.admits(0, 0.30, 0.17, n_points=6)
        assert not gate.admits(0, 0.30, 0.17, n_points=6)
        assert gate.admits(0, 0.30, 0.17, n_points=6)

    def test_a_frame_of_too_few_points_is_no_vote_and_breaks_no_count(self) -> None:
        gate = InitGate(self.CONFIG)
        assert not gate.admits(0, 0.30, 0.170, n_points=5)
        assert not gate.admits(0, 0.90, 0.500, n_points=4)  # not a vote, right or wrong
        assert not gate.admits(0, 0.31, 0.175, n_points=6)
        assert not gate.admits(0, 0.30, 0.170, n_points=3)
        assert gate.admits(0, 0.29, 0.165, n_points=5)
