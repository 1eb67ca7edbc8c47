"""The per-frame pipeline (robot/vision/frame_state.py) on synthetic corridor scenes.

Each scene point gets its own random ZNCC descriptor (the ``harris-zncc`` front end's
kind), so matching pairs a corner
with the same point's corner whenever it lies in the search window: the
correspondences are known exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import FeatureConfig, MatchConfig, PathStateConfig
from robot.vision.features import Features
from robot.vision.frame_state import (
    key_correspondences,
    key_segment_from_key_images,
    state_from_frame,
)
from robot.vision.front_end import FrontEnd, make_front_end
from robot.vision.image_errors import image_errors
from shared.camera_model import CameraModel
from shared.errors import DegenerateGeometryError, ShapeError
from sim.synthetic.corridor_scene import CorridorScene, SceneView, corridor_scene

CONFIG = PathStateConfig()
PATCH_LENGTH = 121


def descriptors(rng: np.random.Generator, n_points: int) -> np.ndarray:
    """(n_points, 121) float32 zero-mean unit rows: one random descriptor per scene point."""
    table = rng.standard_normal((n_points, PATCH_LENGTH)).astype(np.float32)
    table -= table.mean(axis=1, keepdims=True)
    return table / np.linalg.norm(table, axis=1, keepdims=True)


#: The scenes' lens is the default one.
FRONT_END = make_front_end(FeatureConfig(), CameraModel.default())


def front_end(scene: CorridorScene) -> FrontEnd:
    assert np.array_equal(scene.camera.K, FRONT_END.camera.K)
    return FRONT_END


def features(view: SceneView, table: np.ndarray) -> Features:
    return FRONT_END.features(view.pixels_xy, table[view.point_ids])


def scrambled(f: Features, rng: np.random.Generator) -> Features:
    """The same corners with unrelated descriptors: ZNCC finds nothing."""
    return Features(f.pixels_xy, descriptors(rng, len(f))[rng.permutation(len(f))], f.response,
                    f.bearings)


def true_tracks(a: SceneView, b: SceneView) -> np.ndarray:
    """(K, 2) int64 (corner of a, corner of b) of every point both views see."""
    _, idx_a, idx_b = np.intersect1d(a.point_ids, b.point_ids, return_indices=True)
    return np.column_stack([idx_a, idx_b]).astype(np.int64)


@pytest.fixture
def scene(rng: np.random.Generator) -> CorridorScene:
    return corridor_scene(rng, outlier_ratio=0.0)


class TestKeyCorrespondences:
    def test_zncc_pairs_the_same_points(self, scene: CorridorScene, rng: np.random.Generator
                                        ) -> None:
        table = descriptors(rng, len(scene.points_w))
        pairs = key_correspondences(features(scene.next, table), features(scene.previous, table),
                                    front_end(scene), MatchConfig(search_radius_deg=None))
        assert pairs.n_tracked == 0
        np.testing.assert_array_equal(scene.next.point_ids[pairs.idx_next],
                                      scene.previous.point_ids[pairs.idx_other])
        assert len(pairs.idx_next) == len(true_tracks(scene.next, scene.previous))

    def test_tracks_first_then_zncc_among_the_other_corners(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        table = descriptors(rng, len(scene.points_w))
        tracks = true_tracks(scene.next, scene.previous)[::3]
        pairs = key_correspondences(features(scene.next, table), features(scene.previous, table),
                                    front_end(scene), MatchConfig(search_radius_deg=None), tracks)
        assert pairs.n_tracked == len(tracks)
        np.testing.assert_array_equal(pairs.idx_next[: len(tracks)], tracks[:, 0])
        np.testing.assert_array_equal(pairs.idx_other[: len(tracks)], tracks[:, 1])
        assert len(np.unique(pairs.idx_next)) == len(pairs.idx_next)
        assert len(np.unique(pairs.idx_other)) == len(pairs.idx_other)
        np.testing.assert_array_equal(scene.next.point_ids[pairs.idx_next],
                                      scene.previous.point_ids[pairs.idx_other])
        assert len(pairs.idx_next) == len(true_tracks(scene.next, scene.previous))

    def test_tracks_stand_where_zncc_finds_nothing(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        table = descriptors(rng, len(scene.points_w))
        tracks = true_tracks(scene.next, scene.previous)
        pairs = key_correspondences(features(scene.next, table),
                                    scrambled(features(scene.previous, table), rng),
                                    front_end(scene), CONFIG.matching, tracks)
        assert pairs.n_tracked == len(pairs.idx_next) == len(tracks)

    def test_bad_tracks(self, scene: CorridorScene, rng: np.random.Generator) -> None:
        table = descriptors(rng, len(scene.points_w))
        f_next, f_prev = features(scene.next, table), features(scene.previous, table)
        fe, matching = front_end(scene), CONFIG.matching
        with pytest.raises(ShapeError, match="tracks_next_other"):
            key_correspondences(f_next, f_prev, fe, matching, np.zeros(4, np.int64))
        with pytest.raises(ValueError, match=r"column 1 must index the .* other key image"):
            key_correspondences(f_next, f_prev, fe, matching, [[0, len(f_prev)]])
        with pytest.raises(ValueError, match="column 0 must index"):
            key_correspondences(f_next, f_prev, fe, matching, [[-1, 0]])


def run(scene: CorridorScene, rng: np.random.Generator, scramble_previous: bool = False,
        tracks: np.ndarray | None = None):
    table = descriptors(rng, len(scene.points_w))
    f_prev = features(scene.previous, table)
    if scramble_previous:
        f_prev = scrambled(f_prev, rng)
    segment = key_segment_from_key_images(
        features(scene.next, table), f_prev, scene.odom_next, scene.odom_previous, front_end(scene),
        scene.mount, rng, CONFIG, tracks,
    )
    return segment, state_from_frame(features(scene.current, table), segment, front_end(scene),
                                     scene.mount, rng, CONFIG)


class TestStateFromFrame:
    def test_known_answer_on_corridor_scenes(self, rng: np.random.Generator) -> None:
        y_err, theta_err = [], []
        for _ in range(12):
            scene = corridor_scene(rng, outlier_ratio=0.0)
            segment, result = run(scene, rng)
            assert segment.key_pair.ok and result.state.ok
            assert result.state.scale_source == "three-view"
            y_err.append(abs(result.state.y_m - scene.y_m))
            theta_err.append(abs(math.degrees(result.state.theta_rad - scene.theta_rad)))
        assert np.median(y_err) <= 0.02 and max(y_err) <= 0.06
        assert np.median(theta_err) <= 0.5 and max(theta_err) <= 1.5

    def test_image_errors_are_measured_on_the_inliers(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        _, result = run(scene, rng)
        n_inliers = int(np.count_nonzero(result.state.inlier_mask))
        assert result.state.inlier_mask.shape == (result.matches,)
        assert result.image_errors.n_points == n_inliers > 0
        assert result.image_errors.err_image_max_px >= result.image_errors.err_points_px > 0

    def test_the_key_images_corners_go_with_the_frames_in_order(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        segment, result = run(scene, rng)
        assert result.key_xy.shape == result.matched_xy.shape == (result.matches, 2)
        key_corners = {tuple(xy) for xy in segment.next_features.pixels_xy}
        assert all(tuple(xy) in key_corners for xy in result.key_xy)
        inliers = result.state.inlier_mask
        again = image_errors(result.matched_xy[inliers], result.key_xy[inliers])
        assert again.err_image_max_px == result.image_errors.err_image_max_px

    def test_teach_tracks_give_the_key_pair_matching_cannot(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        segment, result = run(scene, rng, scramble_previous=True)
        assert not segment.key_pair.ok and not result.state.ok
        assert result.image_errors.n_points == np.count_nonzero(result.state.inlier_mask)
        tracks = true_tracks(scene.next, scene.previous)
        segment, result = run(scene, rng, scramble_previous=True, tracks=tracks)
        assert segment.key_pair.ok and result.state.ok
        assert segment.correspondences.n_tracked == len(tracks)
        assert abs(result.state.y_m - scene.y_m) <= 0.06

    def test_no_corners_in_the_frame(self, scene: CorridorScene, rng: np.random.Generator
                                     ) -> None:
        table = descriptors(rng, len(scene.points_w))
        segment = key_segment_from_key_images(
            features(scene.next, table), features(scene.previous, table), scene.odom_next,
            scene.odom_previous, front_end(scene), scene.mount, rng, CONFIG,
        )
        result = state_from_frame(Features.empty(121), segment, front_end(scene), scene.mount,
                                  rng, CONFIG)
        assert not result.state.ok and result.matches == 0
        assert result.image_errors.err_image_max_px == np.inf

    def test_key_images_at_one_place_are_degenerate(
        self, scene: CorridorScene, rng: np.random.Generator
    ) -> None:
        table = descriptors(rng, len(scene.points_w))
        with pytest.raises(DegenerateGeometryError, match="apart by odometry"):
            key_segment_from_key_images(
                features(scene.next, table), features(scene.previous, table), scene.odom_next,
                scene.odom_next, front_end(scene), scene.mount, rng, CONFIG,
            )
