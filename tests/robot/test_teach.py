"""Key image selection (robot/teach.py) on synthetic frame streams with known shared points."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.config import FeatureConfig, TeachConfig
from robot.teach import KeyImageSelector, select_key_images
from shared.errors import InputError
from tests.robot.blob_frames import blob_camera, cell_centre, frames_from_schedule, render

#: The frames' points are smooth saddles, one Harris corner each: the paper's front end.
FEATURES = FeatureConfig(method="harris-zncc")


def staggered(frames: int, lifetime: int) -> list[list[int]]:
    """Point p is visible in frames p - lifetime + 1 .. p: every frame shows ``lifetime`` points,
    and a point seen in frame j is still seen in frame k > j iff p >= k."""
    return [list(range(k, k + lifetime)) for k in range(frames)]


def select(visible: list[list[int]], config: TeachConfig, rng: np.random.Generator):
    return select_key_images(frames_from_schedule(visible, rng), blob_camera(), FEATURES, config)


def teach_config(m: int, **changes: object) -> TeachConfig:
    """M exactly (no reduction for key images with few corners) and no spacing bound (the
    frames are 0.1 m apart), unless ``changes`` say so."""
    return TeachConfig(min_tracked_points=m, **{"min_tracked_fraction": 1.0,
                                                "max_spacing_m": 1e9, **changes})


def oracle(
    visible: list[list[int]], m: int, max_missed: int, fraction: float = 1.0
) -> list[tuple[int, int]]:
    """The selection rule on sets of point ids: (frame index, shared points) of each key image."""
    keys = [(0, 0)]
    m_full = m
    while True:
        key = keys[-1][0]
        m = max(1, min(m_full, math.ceil(fraction * len(visible[key]))))
        missed = dict.fromkeys(visible[key], 0)
        after: list[tuple[int, int]] = []
        candidate = None
        for j in range(key + 1, len(visible)):
            missed = {p: 0 if p in visible[j] else n + 1 for p, n in missed.items()}
            missed = {p: n for p, n in missed.items() if n <= max_missed}
            shared = sum(n == 0 for n in missed.values())
            after.append((j, shared))
            if shared >= m:
                candidate = (j, shared)
            if len(missed) < m:
                keys.append(candidate or after[0])
                break
        else:
            if after:
                keys.append(after[-1])
            return keys


class TestKeyImageSelection:
    def test_key_images_every_ten_frames_when_one_point_is_lost_per_frame(
        self, rng: np.random.Generator
    ) -> None:
        # Key image j shares 40 - (k - j) points with frame k: M = 30 puts the next at j + 10.
        selected = select(staggered(55, 40), teach_config(30), rng)
        assert [s.frame_index for s in selected] == [0, 10, 20, 30, 40, 50, 54]
        assert [s.shared_points for s in selected] == [0, 30, 30, 30, 30, 30, 36]

    def test_a_turn_closes_the_segment_before_the_points_run_out(
        self, rng: np.random.Generator
    ) -> None:
        # The same 40 points in every frame (M = 30 is never short), turning 4 deg per frame:
        # the key image is the last frame within 15 deg of the previous one.
        frames = [(t, image, (x, y, math.radians(4.0 * k)))
                  for k, (t, image, (x, y, _)) in enumerate(
                      frames_from_schedule([list(range(40))] * 13, rng))]
        selected = select_key_images(frames, blob_camera(), FEATURES,
                                     teach_config(30, max_turn_deg=15.0))
        assert [s.frame_index for s in selected] == [0, 3, 6, 9, 12]

    def test_a_long_straight_run_gets_a_key_image_every_max_spacing(
        self, rng: np.random.Generator
    ) -> None:
        # The same 40 points in every frame, 0.1 m apart: the key image is the last frame
        # within 0.35 m of the previous one.
        selected = select(staggered(13, 40)[:1] * 13, teach_config(30, max_spacing_m=0.35),
                          rng)
        assert [s.frame_index for s in selected] == [0, 3, 6, 9, 12]

    def test_turning_the_other_way_across_pi_counts_the_short_way(
        self, rng: np.random.Generator
    ) -> None:
        wrapped = [math.remainder(math.radians(170.0 + 4.0 * k), math.tau) for k in range(7)]
        frames = [(t, image, (x, y, wrapped[k]))
                  for k, (t, image, (x, y, _)) in enumerate(
                      frames_from_schedule([list(range(40))] * 7, rng))]
        selected = select_key_images(frames, blob_camera(), FEATURES,
                                     teach_config(30, max_turn_deg=15.0))
        assert [s.frame_index for s in selected] == [0, 3, 6]

    @pytest.mark.parametrize("max_missed", [0, 1, 3])
    def test_the_gap_tolerance_does_not_move_the_key_images(
        self, rng: np.random.Generator, max_missed: int
    ) -> None:
        config = teach_config(25, max_missed_frames=max_missed)
        selected = select(staggered(40, 40), config, rng)
        assert [s.frame_index for s in selected] == [0, 15, 30, 39]

    def test_a_blinking_point_survives_only_within_the_gap_tolerance(
        self, rng: np.random.Generator
    ) -> None:
        # 20 points always visible; 10 more vanish in frame 1 only. M = 25.
        visible = [list(range(30)), list(range(20)), *[list(range(30))] * 4]
        tolerant = select(visible, teach_config(25, max_missed_frames=1), rng)
        assert [s.frame_index for s in tolerant] == [0, 5]
        assert tolerant[-1].shared_points == 30
        strict = select(visible, teach_config(25, max_missed_frames=0), rng)
        # Frame 1 shares 20 < 25 and the 10 blinking points die: frame 1 is forced.
        assert [s.frame_index for s in strict][:2] == [0, 1]
        assert strict[1].shared_points == 20

    def test_a_blank_frame_forces_the_next_key_images(self, rng: np.random.Generator) -> None:
        # Frame 1 is flat (no corners at all), frames 2 and 3 show new points only.
        later = list(range(30, 60))
        frames = frames_from_schedule([list(range(30)), [], later, later], rng)
        frames[1] = (frames[1][0], np.full_like(frames[1][1], 100), frames[1][2])
        selected = select_key_images(
            frames, blob_camera(), FEATURES, teach_config(10)
        )
        # Nothing after key image 0 shares 10 points: frame 1 is forced; frame 1 has no
        # points to share, so frame 2 is forced too; frame 3 closes the path.
        shared = [(s.frame_index, s.shared_points) for s in selected]
        assert shared == [(0, 0), (1, 0), (2, 0), (3, 30)]

    def test_few_corners_lower_the_threshold(self, rng: np.random.Generator) -> None:
        # 40 corners per key image, half of them needed: key images every 20 frames (M = 30
        # alone would put them every 10).
        config = teach_config(30, min_tracked_fraction=0.5)
        selected = select(staggered(45, 40), config, rng)
        assert [s.frame_index for s in selected] == [0, 20, 40, 44]

    def test_the_default_fraction_is_below_the_per_frame_match_rate(
        self, rng: np.random.Generator
    ) -> None:
        # A sparse key image of 40 corners; every later frame matches 45 % of them (18),
        # the lowest frame-to-frame rate measured in the campus corridor. The default
        # threshold (ceil(0.35 * 40) = 14) keeps them in one segment; a threshold of 20
        # (fraction 0.5) would force a key image at frame 1.
        visible = [list(range(40)), *[list(range(18))] * 10]
        selected = select(visible, TeachConfig(), rng)
        assert [(s.frame_index, s.shared_points) for s in selected] == [(0, 0), (10, 18)]

    @settings(max_examples=12, deadline=None)
    @given(
        seed=st.integers(0, 2**32 - 1),
        m=st.integers(8, 30),
        max_missed=st.integers(0, 2),
        fraction=st.sampled_from([0.3, 0.6, 1.0]),
    )
    def test_matches_the_rule_on_point_sets(
        self, seed: int, m: int, max_missed: int, fraction: float
    ) -> None:
        # Random lifetimes and blinks; the images must give what the rule gives on the sets.
        rng = np.random.default_rng(seed)
        n_frames = 30
        births = np.sort(rng.integers(-20, n_frames, size=70))
        lifetimes = rng.integers(3, 30, size=70)
        visible = []
        for k in range(n_frames):
            shown = [
                p
                for p in range(70)
                if births[p] <= k < births[p] + lifetimes[p] and rng.random() > 0.05
            ]
            visible.append(shown)
        # A point id is its own cell only while 77 cells cover 70 points.
        config = teach_config(m, max_missed_frames=max_missed, min_tracked_fraction=fraction)
        got = [(s.frame_index, s.shared_points) for s in select(visible, config, rng)]
        assert got == oracle(visible, m, max_missed, fraction)


class TestRecords:
    def test_records_carry_time_odometry_distance_and_features(
        self, rng: np.random.Generator
    ) -> None:
        frames = frames_from_schedule(staggered(25, 40), rng, step_m=0.1)
        config = teach_config(30)
        selected = select_key_images(frames, blob_camera(), FEATURES, config)
        second = selected[1]
        assert second.frame_index == 10
        assert second.record.t_ns == frames[10][0]
        assert second.record.odom_pose == pytest.approx((1.0, 0.0, 0.0))
        assert second.record.distance_m == pytest.approx(1.0)
        assert np.array_equal(second.record.image, frames[10][1])
        assert second.record.pixels_xy.shape == (40, 2)
        assert second.record.patches.shape == (40, 11**2)  # 11 px patches on the default lens

    def test_tracks_pair_the_shared_points_of_consecutive_key_images(
        self, rng: np.random.Generator
    ) -> None:
        visible = staggered(55, 40)
        selected = select(visible, teach_config(30), rng)
        assert selected[0].record.tracked_from_previous.shape == (0, 2)
        for previous, current in itertools.pairwise(selected):
            tracks = current.record.tracked_from_previous
            assert tracks.dtype == np.int64 and len(tracks) == current.shared_points
            xy_previous = previous.record.pixels_xy[tracks[:, 0]]
            xy_current = current.record.pixels_xy[tracks[:, 1]]
            np.testing.assert_allclose(xy_previous, xy_current, atol=0.5)
            common = set(visible[previous.frame_index]) & set(visible[current.frame_index])
            assert {tuple(xy) for xy in np.rint(xy_current)} == {cell_centre(p) for p in common}

    def test_distance_sums_the_odometry_steps(self, rng: np.random.Generator) -> None:
        # A square of 1 m sides: 4 m travelled, back at the start.
        corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)]
        frames = [(k, render([0], rng), (x, y, 0.0)) for k, (x, y) in enumerate(corners)]
        selected = select_key_images(frames, blob_camera(), FEATURES, TeachConfig())
        assert selected[-1].record.distance_m == pytest.approx(4.0)

    def test_one_frame_is_one_key_image(self, rng: np.random.Generator) -> None:
        selector = KeyImageSelector(blob_camera(), FEATURES, TeachConfig())
        assert len(selector.push(0, render(range(5), rng), (0.0, 0.0, 0.0))) == 1
        assert selector.finish() == ()

    def test_no_frames_no_key_images(self) -> None:
        assert select_key_images([], blob_camera(), FEATURES, TeachConfig()) == []


class TestBadFrames:
    @pytest.fixture
    def selector(self, rng: np.random.Generator) -> KeyImageSelector:
        selector = KeyImageSelector(blob_camera(), FEATURES, TeachConfig())
        selector.push(100, render(range(5), rng), (0.0, 0.0, 0.0))
        return selector

    @pytest.mark.parametrize(
        ("t_ns", "image", "pose", "message"),
        [
            (200, np.zeros((10, 10), np.uint8), (0.0, 0.0, 0.0), "expected a 320x200 uint8"),
            (200, np.zeros((200, 320), np.float32), (0.0, 0.0, 0.0), "dtype float32"),
            (100, np.zeros((200, 320), np.uint8), (0.0, 0.0, 0.0), "t_ns 100 is not after"),
            (200, np.zeros((200, 320), np.uint8), (0.0, float("nan"), 0.0), "3 finite numbers"),
        ],
    )
    def test_names_the_frame_and_the_problem(
        self, selector: KeyImageSelector, t_ns: int, image: np.ndarray, pose: tuple, message: str
    ) -> None:
        with pytest.raises(InputError, match=f"teach frame 1: .*{message}"):
            selector.push(t_ns, image, pose)


def test_teach_config_is_validated() -> None:
    from robot.config import VmnavConfig
    from shared.config import from_mapping
    from shared.errors import ConfigError

    config = from_mapping(VmnavConfig, {"teach": {"min_tracked_points": 12}}, "f.toml")
    assert config.teach == dataclasses.replace(TeachConfig(), min_tracked_points=12)
    with pytest.raises(ConfigError, match=r"f.toml: teach: min_tracked_points must be >= 1"):
        from_mapping(VmnavConfig, {"teach": {"min_tracked_points": 0}}, "f.toml")
    with pytest.raises(ConfigError, match=r"teach.tracking: search_radius_deg must be in"):
        from_mapping(VmnavConfig, {"teach": {"tracking": {"search_radius_deg": -1.0}}}, "f.toml")
