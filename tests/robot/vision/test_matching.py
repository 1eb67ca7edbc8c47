"""Tests of robot/vision/matching.py: matching with window and unicity (ZNCC patches and
bit strings)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robot.config import FeatureConfig, MatchConfig
from robot.vision.features import Features, Keypoints, detect_harris
from robot.vision.matching import Matches, match_features
from shared.errors import ShapeError
from sim.synthetic.image_pairs import similarity_homography, transform_pixels, warped_pair

FEATURES = FeatureConfig()
CONFIG = MatchConfig()


#: The test lens: pixel (x, y) looks x / S to the right and y / S down, rad.
S_PX_PER_RAD = 174.0


def _bearings(pixels_xy: np.ndarray) -> np.ndarray:
    yaw, pitch = np.asarray(pixels_xy, dtype=float).reshape(-1, 2).T / S_PX_PER_RAD
    return np.column_stack([np.sin(yaw) * np.cos(pitch), np.sin(pitch),
                            np.cos(yaw) * np.cos(pitch)])


def _deg(px: float) -> float:
    """A pixel distance on the test lens as an angle, degrees."""
    return float(np.degrees(px / S_PX_PER_RAD))


def _feats(pixels_xy: np.ndarray, descriptors: np.ndarray, response: np.ndarray) -> Features:
    """Features with the test lens's bearings."""
    return Features(pixels_xy, descriptors, response, _bearings(pixels_xy))


def _harris(image: np.ndarray, config: FeatureConfig) -> Features:
    found: Keypoints = detect_harris(image, config)
    return _feats(found.pixels_xy, found.descriptors, found.response)


def _random_features(rng: np.random.Generator, n: int, extent_px: int, side: int = 3) -> Features:
    """n features at random integer positions in [0, extent_px]^2 with random unit patches."""
    patches = rng.standard_normal((n, side * side))
    patches -= patches.mean(axis=1, keepdims=True)
    patches /= np.linalg.norm(patches, axis=1, keepdims=True)
    pixels = rng.integers(0, extent_px + 1, (n, 2)).astype(np.float64)
    return _feats(pixels, patches, np.ones(n))


def _brute_force(feats_a: Features, feats_b: Features, config: MatchConfig) -> set[tuple[int, int]]:
    """The paper's rule written as plain loops: best in window, threshold, mutual best."""
    scores = feats_a.descriptors @ feats_b.descriptors.T
    r = config.search_radius_deg

    def candidate(i: int, j: int) -> bool:
        cosine = float(feats_a.bearings[i] @ feats_b.bearings[j])
        return r is None or cosine >= np.cos(np.radians(r))

    def best(items: list[int], score: list[float]) -> int | None:
        return items[int(np.argmax(score))] if items else None

    n, m = len(feats_a), len(feats_b)
    out = set()
    for i in range(n):
        cands = [j for j in range(m) if candidate(i, j)]
        j = best(cands, [scores[i, k] for k in cands])
        if j is None or scores[i, j] < config.min_zncc:
            continue
        back = [k for k in range(n) if candidate(k, j)]
        if best(back, [scores[k, j] for k in back]) == i:
            out.add((i, j))
    return out


def _shifted_matches(shift_xy: tuple[float, float], seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Matched pixels between a texture and its shifted, re-lit, noisy copy."""
    pair = warped_pair(np.random.default_rng(seed), similarity_homography(shift_xy),
                       width=400, height=300, noise_sigma=2.0, gain=0.75, offset=25.0)
    feats_a = _harris(pair.image_a, FEATURES)
    feats_b = _harris(pair.image_b, FEATURES)
    return match_features(feats_a, feats_b, CONFIG).pixels_xy(feats_a, feats_b)


class TestMatches:
    def test_pixels_xy(self) -> None:
        feats_a = _feats(np.array([[1.0, 2.0], [3.0, 4.0]]), np.zeros((2, 9)), np.zeros(2))
        pixels_b = np.array([[5.0, 6.0], [7.0, 8.0], [9.0, 10.0]])
        feats_b = _feats(pixels_b, np.zeros((3, 9)), np.zeros(3))
        matches = Matches(np.array([1]), np.array([2]), np.array([0.9]))
        pixels_a, pixels_b = matches.pixels_xy(feats_a, feats_b)
        np.testing.assert_array_equal(pixels_a, [[3.0, 4.0]])
        np.testing.assert_array_equal(pixels_b, [[9.0, 10.0]])
        assert len(matches) == 1
        with pytest.raises(ValueError, match="read-only"):
            matches.idx_a[0] = 0

    def test_shape_errors(self) -> None:
        with pytest.raises(ShapeError, match="idx_b"):
            Matches(np.zeros(2), np.zeros(3), np.zeros(2))
        with pytest.raises(ShapeError, match="score"):
            Matches(np.zeros(2), np.zeros(2), np.zeros((2, 1)))


class TestMatchFeatures:
    def test_smoke(self, rng: np.random.Generator) -> None:
        feats = _random_features(rng, 20, 100)
        matches = match_features(feats, feats, CONFIG)
        assert matches.idx_a.dtype == np.intp and matches.score.dtype == np.float32
        assert len(matches) == 20

    def test_patch_size_mismatch(self, rng: np.random.Generator) -> None:
        with pytest.raises(ShapeError, match="descriptors differ, 9 x float32 and 25 x float32"):
            match_features(_random_features(rng, 4, 50, 3), _random_features(rng, 4, 50, 5), CONFIG)

    @pytest.mark.parametrize("shift_xy", [(7.0, -4.0), (5.4, 3.7), (-12.25, 0.6)])
    def test_recovers_shift(self, shift_xy: tuple[float, float]) -> None:
        pixels_a, pixels_b = _shifted_matches(shift_xy, seed=11)
        displacement = pixels_b - pixels_a
        inliers = np.linalg.norm(displacement - shift_xy, axis=1) <= 2.0
        assert len(pixels_a) >= 60
        assert inliers.mean() > 0.9
        np.testing.assert_allclose(np.median(displacement[inliers], axis=0), shift_xy, atol=0.15)

    def test_recovers_homography(self) -> None:
        H_b_a = similarity_homography(
            (10.0, -6.0), np.radians(2.0), 1.02, (200.0, 150.0), (1e-5, 0.0)
        )
        pair = warped_pair(np.random.default_rng(3), H_b_a, 400, 300, gain=1.2, offset=-15.0)
        feats_a = _harris(pair.image_a, FEATURES)
        feats_b = _harris(pair.image_b, FEATURES)
        pixels_a, pixels_b = match_features(feats_a, feats_b, CONFIG).pixels_xy(feats_a, feats_b)
        error_px = np.linalg.norm(transform_pixels(H_b_a, pixels_a) - pixels_b, axis=1)
        assert len(error_px) >= 60 and np.mean(error_px <= 2.0) > 0.9

    def test_unicity(self, rng: np.random.Generator) -> None:
        # Many near-duplicate patches: without the mutual check, several A would pick one B.
        feats_a = _random_features(rng, 60, 40)
        base = feats_a.descriptors[0]
        noisy = base + 0.3 * rng.standard_normal((80, base.shape[0]))
        noisy -= noisy.mean(axis=1, keepdims=True)
        noisy /= np.linalg.norm(noisy, axis=1, keepdims=True)
        feats_b = _feats(rng.integers(0, 41, (80, 2)).astype(float), noisy, np.ones(80))
        matches = match_features(feats_a, feats_b, dataclasses.replace(CONFIG, min_zncc=-1.0))
        assert len(matches) > 0
        assert len(np.unique(matches.idx_a)) == len(matches)
        assert len(np.unique(matches.idx_b)) == len(matches)

    def test_window_is_respected(self, rng: np.random.Generator) -> None:
        # B's twin of A lies `angle` away: found within a cone a little wider, not narrower.
        feats_a = _random_features(rng, 1, 0)
        shifted = feats_a.pixels_xy + np.array([[11.0, -3.0]])
        feats_b = _feats(shifted, feats_a.descriptors, np.ones(1))
        angle = np.degrees(np.arccos(feats_a.bearings[0] @ feats_b.bearings[0]))
        for radius, found in ((angle * 1.001, 1), (angle * 0.999, 0), (None, 1)):
            config = dataclasses.replace(CONFIG, search_radius_deg=radius)
            assert len(match_features(feats_a, feats_b, config)) == found

    def test_window_is_respected_on_images(self) -> None:
        pair = warped_pair(np.random.default_rng(4), similarity_homography((9.0, 0.0)), 400, 300)
        feats_a = _harris(pair.image_a, FEATURES)
        feats_b = _harris(pair.image_b, FEATURES)
        matches = match_features(feats_a, feats_b,
                                 dataclasses.replace(CONFIG, search_radius_deg=_deg(6.0)))
        cosines = np.einsum("kd,kd->k", feats_a.bearings[matches.idx_a],
                            feats_b.bearings[matches.idx_b])
        assert len(matches) > 20
        assert np.all(cosines >= np.cos(np.radians(_deg(6.0))))

    def test_threshold(self, rng: np.random.Generator) -> None:
        feats_a, feats_b = _random_features(rng, 30, 20), _random_features(rng, 30, 20)
        matches = match_features(feats_a, feats_b, dataclasses.replace(CONFIG, min_zncc=0.3))
        assert np.all(matches.score >= 0.3)
        expected = feats_a.descriptors[matches.idx_a] @ feats_b.descriptors[matches.idx_b].T
        np.testing.assert_allclose(matches.score, np.diag(expected), atol=1e-6)

    def test_brightness_affine_invariance(self) -> None:
        rng = np.random.default_rng(6)
        image = np.clip(np.rint(warped_pair(rng, np.eye(3), 320, 240).image_a * 0.6 + 40), 0, 255)
        image = image.astype(np.uint8)
        relit = np.clip(np.rint(1.4 * image.astype(float) - 50.0), 0, 255).astype(np.uint8)
        feats_a, feats_b = _harris(image, FEATURES), _harris(relit, FEATURES)
        matches = match_features(feats_a, feats_b, CONFIG)
        pixels_a, pixels_b = matches.pixels_xy(feats_a, feats_b)
        assert len(matches) > 0.9 * len(feats_a)
        assert np.median(matches.score) > 0.99
        assert np.mean(np.linalg.norm(pixels_b - pixels_a, axis=1) <= 0.5) > 0.95

    def test_ratio_test(self, rng: np.random.Generator) -> None:
        # p + e and p - e (e orthogonal to p) are equally close to A's patch p:
        # ambiguous, kept without the ratio test only. One of them with an
        # unrelated patch passes it.
        feats_a = _random_features(rng, 1, 0)
        p = feats_a.descriptors[0].astype(np.float64)
        e = rng.standard_normal(9)
        e -= e.mean() + (e @ p) * p
        e *= 0.2 / np.linalg.norm(e)
        plus, minus = (p + e) / np.linalg.norm(p + e), (p - e) / np.linalg.norm(p - e)
        ratio = dataclasses.replace(CONFIG, max_distance_ratio=0.8)
        apart = np.array([[0.0, 0.0], [30.0, 0.0]])  # 10 degrees: rivals
        ambiguous = _feats(apart, np.stack([plus, minus]), np.ones(2))
        assert len(match_features(feats_a, ambiguous, CONFIG)) == 1
        assert len(match_features(feats_a, ambiguous, ratio)) == 0
        other = _random_features(rng, 1, 0).descriptors[0]
        distinct = _feats(apart, np.stack([other, plus]), np.ones(2))
        matches = match_features(feats_a, distinct, ratio)
        assert matches.idx_b.tolist() == [1]

    @pytest.mark.parametrize(("n", "m"), [(0, 0), (0, 5), (5, 0)])
    def test_empty_inputs(self, n: int, m: int, rng: np.random.Generator) -> None:
        matches = match_features(_random_features(rng, n, 50), _random_features(rng, m, 50), CONFIG)
        assert len(matches) == 0
        assert matches.idx_a.shape == matches.idx_b.shape == matches.score.shape == (0,)

    def test_no_candidates_in_window(self, rng: np.random.Generator) -> None:
        feats_a = _random_features(rng, 5, 10)
        feats_b = _feats(feats_a.pixels_xy + 500.0, feats_a.descriptors, np.ones(5))
        assert len(match_features(feats_a, feats_b, CONFIG)) == 0

    @settings(max_examples=60, deadline=None)
    @given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 40),
           radius=st.sampled_from([None, _deg(1.0), _deg(40.0)]))
    def test_self_match_is_identity(self, seed: int, n: int, radius: float | None) -> None:
        feats = _random_features(np.random.default_rng(seed), n, 200, side=5)
        matches = match_features(feats, feats,
                                 dataclasses.replace(CONFIG, search_radius_deg=radius))
        np.testing.assert_array_equal(matches.idx_a, np.arange(n))
        np.testing.assert_array_equal(matches.idx_b, np.arange(n))
        np.testing.assert_allclose(matches.score, 1.0, atol=1e-5)

    @settings(max_examples=100, deadline=None)
    @given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 15), m=st.integers(0, 15),
           radius=st.sampled_from([None, _deg(3.0), _deg(5.0), _deg(10.0)]),
           min_zncc=st.sampled_from([-1.0, 0.0, 0.4]))
    def test_equals_brute_force(self, seed: int, n: int, m: int, radius: float | None,
                                min_zncc: float) -> None:
        rng = np.random.default_rng(seed)
        feats_a, feats_b = _random_features(rng, n, 12), _random_features(rng, m, 12)
        config = MatchConfig(search_radius_deg=radius, min_zncc=min_zncc)
        matches = match_features(feats_a, feats_b, config)
        found = set(zip(matches.idx_a.tolist(), matches.idx_b.tolist(), strict=True))
        assert found == _brute_force(feats_a, feats_b, config)


class TestBitStrings:
    def test_similarity_is_hamming(self, rng: np.random.Generator) -> None:
        bits_a = rng.integers(0, 256, (30, 32), dtype=np.uint8)
        bits_b = rng.integers(0, 256, (40, 32), dtype=np.uint8)
        feats_a = _feats(rng.uniform(0, 50, (30, 2)), bits_a, np.ones(30))
        feats_b = _feats(rng.uniform(0, 50, (40, 2)), bits_b, np.ones(40))
        for radius in (None, _deg(10.0)):
            matches = match_features(feats_a, feats_b, MatchConfig(search_radius_deg=radius,
                                                                   min_zncc=-1.0))
            assert len(matches) > 0
            hamming = np.unpackbits(bits_a[matches.idx_a] ^ bits_b[matches.idx_b], axis=1).sum(1)
            np.testing.assert_allclose(matches.score, 1.0 - 2.0 * hamming / 256, atol=1e-6)

    def test_finds_the_flipped_copies(self, rng: np.random.Generator) -> None:
        bits = rng.integers(0, 256, (50, 32), dtype=np.uint8)
        noisy = bits ^ (rng.random((50, 32 * 8)) < 0.05).reshape(50, 32, 8).astype(np.uint8).dot(
            1 << np.arange(8)[::-1]).astype(np.uint8)
        order = rng.permutation(50)
        pixels = rng.uniform(0, 400, (50, 2))
        feats_a = _feats(pixels, bits, np.ones(50))
        feats_b = _feats(pixels[order] + 2.0, noisy[order], np.ones(50))
        matches = match_features(feats_a, feats_b, MatchConfig(search_radius_deg=None))
        assert len(matches) == 50
        np.testing.assert_array_equal(order[matches.idx_b], matches.idx_a)

    def test_kinds_must_agree(self, rng: np.random.Generator) -> None:
        bits = _feats(np.zeros((2, 2)), np.zeros((2, 36), np.uint8), np.ones(2))
        with pytest.raises(ShapeError, match="descriptors differ, 36 x uint8 and 36 x float32"):
            match_features(bits, _random_features(rng, 2, 5, side=6), CONFIG)


class TestGuidedSearch:
    def test_cones_turned_by_the_prediction(self, rng: np.random.Generator) -> None:
        feats_a = _random_features(rng, 20, 100)  # within 33 degrees of the axis
        c, s = np.cos(np.radians(25.0)), np.sin(np.radians(25.0))
        R_b_a = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        turned = feats_a.bearings @ R_b_a.T
        feats_b = Features(feats_a.pixels_xy, feats_a.descriptors, np.ones(20), turned)
        config = MatchConfig(search_radius_deg=3.0)
        assert len(match_features(feats_a, feats_b, config)) == 0
        guided = match_features(feats_a, feats_b, config, R_b_a)
        np.testing.assert_array_equal(guided.idx_b, np.arange(20))
        with pytest.raises(ShapeError, match="R_b_a"):
            match_features(feats_a, feats_b, config, np.eye(2))


class TestRatioTestOutsideTheNeighbourhood:
    def test_neighbours_are_not_rivals_but_a_period_away_is(
        self, rng: np.random.Generator
    ) -> None:
        """B holds A's corner twice, 0.5 degrees apart (a corner and its neighbour), and once
        more 5 degrees away (the next period of a pattern)."""
        feats_a = _random_features(rng, 1, 0)
        p = feats_a.descriptors[0]
        ratio = MatchConfig(search_radius_deg=None, max_distance_ratio=0.8,
                            ratio_exclusion_deg=1.5)
        near = np.array([[0.0, 0.0], [_px(0.5), 0.0]])
        feats_b = _feats(near, np.stack([p, p]), np.ones(2))
        assert len(match_features(feats_a, feats_b, ratio)) == 1
        period = np.array([[0.0, 0.0], [_px(0.5), 0.0], [_px(5.0), 0.0]])
        feats_b = _feats(period, np.stack([p, p, p]), np.ones(3))
        assert len(match_features(feats_a, feats_b, ratio)) == 0
        no_exclusion = dataclasses.replace(ratio, ratio_exclusion_deg=0.0)
        assert len(match_features(feats_a, _feats(near, np.stack([p, p]), np.ones(2)),
                                  no_exclusion)) == 0


def _px(deg: float) -> float:
    """An angle on the test lens as a pixel distance."""
    return float(np.radians(deg) * S_PX_PER_RAD)
