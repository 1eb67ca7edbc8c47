"""Localization in the visual memory (robot/memory/localize.py) on textured synthetic places."""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar

import numpy as np
import pytest

from robot.config import LocalizeConfig
from robot.memory import Localizer, localize
from robot.vision.front_end import make_front_end
from shared.config import CameraMountConfig
from shared.memory import VisualMemory
from tests.robot.memory.textured import FEATURES, Place, make_places, memory_of
from tests.shared.memory.builders import small_camera

CONFIG = LocalizeConfig(candidates=4, min_inliers=10)
MOUNT = CameraMountConfig()


@pytest.fixture(scope="module")
def places() -> list[Place]:
    return make_places(np.random.default_rng(11), 12, small_camera())


@pytest.fixture(scope="module")
def memory(places: list[Place]) -> VisualMemory:
    # Key image k is place k, on two paths.
    return memory_of(
        {"a": [p.key_image for p in places[:7]], "b": [p.key_image for p in places[7:]]}
    )


@pytest.fixture(scope="module")
def localizer(memory: VisualMemory) -> Localizer:
    return Localizer.from_memory(memory, MOUNT, FEATURES, CONFIG)


class TestLocalize:
    def test_each_second_view_finds_its_place(
        self, places: list[Place], localizer: Localizer
    ) -> None:
        for place_id, place in enumerate(places):
            result = localizer.localize(place.query, verify_all=True)
            assert result.keyframe_id == place_id and result.ok
            assert result.verdict == "accepted"
            winner, *others = result.candidates
            assert winner.keyframe_id == place_id and winner.accepted
            assert result.inliers == winner.inliers >= 0.5 * winner.matches
            assert len(others) >= CONFIG.candidates - 1  # and the walk's refused neighbours
            assert not any(c.accepted for c in others)
            assert result.inliers >= 2 * max(c.inliers for c in others)

    def test_candidates_that_cannot_win_are_not_verified(
        self, places: list[Place], localizer: Localizer
    ) -> None:
        result = localizer.localize(places[6].query)
        assert result.keyframe_id == 6 and result.ok
        for c in result.candidates[1:]:
            assert c.verification is None or not c.accepted
            if c.verification is None:
                assert c.matches <= result.inliers
        assert "key image 6:" in result.detail and "(accepted)" in result.detail

    def test_a_key_image_is_its_own_best_thumbnail(
        self, places: list[Place], localizer: Localizer
    ) -> None:
        result = localizer.localize(places[3].key_image)
        assert result.candidates[0].keyframe_id == 3
        assert result.candidates[0].similarity == pytest.approx(1.0, abs=1e-5)
        assert result.candidates[0].verification is not None
        assert result.candidates[0].verification.yaw_deg == pytest.approx(0.0, abs=0.1)

    def test_exhaustive_agrees_and_verifies_every_key_image(
        self, places: list[Place], localizer: Localizer
    ) -> None:
        result = localizer.localize_exhaustive(places[9].query)
        assert result.keyframe_id == 9
        assert [c.keyframe_id for c in result.candidates] == list(range(12))
        assert all(math.isnan(c.similarity) for c in result.candidates)
        assert [c.verification is not None for c in result.candidates].count(True) == 1
        assert result.verdict == "accepted"
        fast = localizer.localize(places[9].query)
        assert fast.matches == result.matches and fast.inliers == result.inliers
        assert result.ok

    def test_one_candidate_is_the_prefilter_alone(
        self, places: list[Place], memory: VisualMemory
    ) -> None:
        one = Localizer.from_memory(memory, MOUNT, FEATURES,
                                    dataclasses.replace(CONFIG, candidates=1))
        result = one.localize(places[5].query)
        assert result.keyframe_id == 5 and result.candidates[0].keyframe_id == 5
        # The walk verified a path neighbour the prefilter passed over (another place).
        walked = result.candidates[1:]
        assert {c.keyframe_id for c in walked} <= {4, 6} and not any(c.accepted for c in walked)

    def test_a_subset_of_key_images(self, places: list[Place], memory: VisualMemory) -> None:
        subset = Localizer.from_memory(memory, MOUNT, FEATURES, CONFIG, keyframe_ids=[0, 1, 2])
        assert subset.keyframe_ids == (0, 1, 2)
        result = subset.localize(places[8].query)
        assert result.keyframe_id in (0, 1, 2)
        assert not result.ok  # place 8 is none of them: chance matches only
        assert result.verdict != "accepted"
        assert result.detail.startswith(f"key image {result.keyframe_id}: ")

    def test_the_convenience_function(self, places: list[Place], memory: VisualMemory) -> None:
        assert localize(memory, places[2].query, MOUNT, FEATURES, CONFIG).keyframe_id == 2

    def test_an_empty_set_of_key_images(self, places: list[Place], memory: VisualMemory) -> None:
        nothing = Localizer.from_memory(memory, MOUNT, FEATURES, CONFIG, keyframe_ids=[])
        result = nothing.localize(places[0].query)
        assert result.keyframe_id is None and result.matches == 0 and not result.ok
        assert result.inliers == 0 and result.verdict == "no key images"
        assert nothing.localize_exhaustive(places[0].query).candidates == ()


class TestPrefilter:
    def test_a_sideways_shift_is_forgiven(self, places: list[Place], memory: VisualMemory) -> None:
        # 8 px of the 160 px image is 4 thumbnail px: within the default 6 px of shifts.
        shifted = np.roll(places[4].key_image, 8, axis=1)
        tolerant = Localizer.from_memory(memory, MOUNT, FEATURES, CONFIG)
        rigid = Localizer.from_memory(
            memory, MOUNT, FEATURES, dataclasses.replace(CONFIG, prefilter_max_shift_px=0)
        )
        best = tolerant.localize(shifted).candidates[0]
        assert best.keyframe_id == 4 and best.similarity > 0.8
        rigid_similarity = {c.keyframe_id: c.similarity for c in rigid.localize(shifted).candidates}
        assert rigid_similarity.get(4, -1.0) < 0.5


class TestBadInput:
    @pytest.mark.parametrize(
        ("image", "message"),
        [
            (np.zeros((60, 80), np.uint8), "expected a 160x120 uint8 grey image, got shape"),
            (np.zeros((120, 160), np.float64), "dtype float64"),
            (np.zeros((0, 0), np.uint8), "shape \\(0, 0\\)"),
            (np.zeros((120, 160, 3), np.uint8), "shape \\(120, 160, 3\\)"),
        ],
    )
    def test_the_query_image(self, localizer: Localizer, image: np.ndarray, message: str) -> None:
        with pytest.raises(ValueError, match=f"query image: .*{message}"):
            localizer.localize(image)
        with pytest.raises(ValueError, match="query image"):
            localizer.localize_exhaustive(image)

    def test_inconsistent_inputs(self, memory: VisualMemory) -> None:
        keyframe = memory.keyframe(0)
        with pytest.raises(ValueError, match="2 key image ids, 1 thumbnails"):
            Localizer([0, 1], [keyframe.thumbnail], [], memory.camera, MOUNT, FEATURES, CONFIG)
        features = [make_front_end(FEATURES, memory.camera).features_from_keyframe(keyframe)]
        with pytest.raises(ValueError, match="thumbnail 0: expected 80x60 uint8, got shape"):
            Localizer([0], [keyframe.image], features, memory.camera, MOUNT, FEATURES, CONFIG)


def test_localize_config_is_validated() -> None:
    from robot.config import VmnavConfig
    from shared.config import from_mapping
    from shared.errors import ConfigError

    config = from_mapping(VmnavConfig, {"localize": {"candidates": 5}}, "f.toml")
    assert config.localize.candidates == 5
    assert config.localize.matching.search_radius_deg is None
    with pytest.raises(ConfigError, match="localize: prefilter_window_px must be odd"):
        from_mapping(VmnavConfig, {"localize": {"prefilter_window_px": 4}}, "f.toml")


def scripted_localizer(memory: VisualMemory, config: LocalizeConfig, inliers: dict[int, int],
                       along: dict[int, float], monkeypatch: pytest.MonkeyPatch
                       ) -> tuple[Localizer, list[int]]:
    """A localizer whose matching and verification are scripted per key image: ``inliers``
    (accepted when not 0; 5 more matches) and ``along`` (nan when not given); the list
    collects the key images verified, in order."""
    from robot.memory.verification import ACCEPTED, TOO_FEW_INLIERS, Verification
    from robot.vision.matching import Matches

    localizer = Localizer.from_memory(memory, MOUNT, FEATURES, config)
    verified: list[int] = []
    ids = localizer.keyframe_ids

    def match(query: object, key: object, matching: object) -> Matches:
        k = next(i for i, f in zip(ids, localizer._features, strict=True) if f is key)
        n = inliers.get(k, 10) + 5
        return Matches(np.arange(n), np.arange(n), np.ones(n))

    def verify(query: object, k: int, matches: Matches, rng: object) -> Verification:
        keyframe_id = ids[k]
        verified.append(keyframe_id)
        n = inliers.get(keyframe_id, 0)
        return Verification(len(matches), n, n / len(matches), 0.0, 0.0,
                            ACCEPTED if n else TOO_FEW_INLIERS, along.get(keyframe_id, math.nan))

    monkeypatch.setattr(localizer._front_end, "match", match)
    monkeypatch.setattr(localizer, "_verify", verify)
    return localizer, verified


class TestPathSupport:
    """Step 3: among accepted key images, the one whose path neighbours agree wins."""

    # Scripted inliers per key image: key image 3 alone has the most; 8, 9, 10 are a run of
    # consecutive key images that all see the query (as on a path through a far scene).
    INLIERS: ClassVar[dict[int, int]] = {3: 40, 8: 38, 9: 37, 10: 36}

    def scripted(self, places: list[Place], memory: VisualMemory, weight: float,
                 monkeypatch: pytest.MonkeyPatch) -> tuple[Localizer, list[int]]:
        config = dataclasses.replace(CONFIG, candidates=len(places), neighbour_weight=weight)
        return scripted_localizer(memory, config, self.INLIERS, {}, monkeypatch)

    def test_the_supported_key_image_wins(self, places: list[Place], memory: VisualMemory,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, verified = self.scripted(places, memory, 0.5, monkeypatch)
        result = localizer.localize(places[9].query)
        assert result.ok and result.keyframe_id == 9 and result.inliers == 37
        winner = result.candidates[0]
        assert winner.support == pytest.approx(37 + 0.5 * (38 + 36))
        assert {8, 9, 10} <= set(verified) and len(verified) == len(set(verified))

    def test_weight_zero_is_the_most_inliers(self, places: list[Place], memory: VisualMemory,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, verified = self.scripted(places, memory, 0.0, monkeypatch)
        result = localizer.localize(places[9].query)
        assert result.ok and result.keyframe_id == 3
        # Those whose match counts could beat 40 inliers are verified, most matches first.
        assert verified == [3, 8, 9, 10]


class TestWalkAlongThePath:
    """Step 4: from the winner, towards the side the query lies on, to the first key image
    ahead of the query."""

    def scripted(self, places: list[Place], memory: VisualMemory, inliers: dict[int, int],
                 along: dict[int, float], monkeypatch: pytest.MonkeyPatch,
                 steps: int = 3) -> tuple[Localizer, list[int]]:
        config = dataclasses.replace(CONFIG, candidates=len(places), bracket_steps=steps)
        return scripted_localizer(memory, config, inliers, along, monkeypatch)

    # Path "a" holds key images 0-6 in order. The query lies between 3 and 4; 5, the
    # second key image ahead of it, has the most inliers.
    INLIERS: ClassVar[dict[int, int]] = {2: 25, 3: 30, 4: 35, 5: 40}
    ALONG: ClassVar[dict[int, float]] = {2: 0.8, 3: 0.2, 4: -0.6, 5: -0.9}

    def test_the_walk_goes_back_to_the_pair_around_the_query(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, verified = self.scripted(places, memory, self.INLIERS, self.ALONG,
                                            monkeypatch)
        result = localizer.localize(places[3].query)
        # 3 and 4 bracket it: nearer 3 along the path (|0.2| < |-0.6|), and 4 is ahead.
        assert result.ok and result.keyframe_id == 3 and result.inliers == 30
        assert result.ahead_id == 4
        assert result.candidates[0].keyframe_id == 3
        assert result.candidates[1].keyframe_id == 5  # then the ranking by inliers
        assert verified[-2:] == [4, 3] and 2 not in verified

    def test_a_query_ahead_of_the_winner_is_walked_forward(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        # Mirror: 1 has the most inliers and sees the query ahead; it lies between 2 and 3,
        # nearer 3.
        inliers = {1: 40, 2: 35, 3: 30}
        along = {1: 0.9, 2: 0.5, 3: -0.1}
        localizer, _ = self.scripted(places, memory, inliers, along, monkeypatch)
        result = localizer.localize(places[3].query)
        assert (result.keyframe_id, result.ahead_id) == (3, 3)

    def test_a_query_ahead_of_every_key_image_walked_starts_after_them(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        # 1 and 2 see the query ahead; 3, refused, cannot bracket it: 3 is the first ahead.
        inliers = {1: 40, 2: 35}
        along = {1: 0.9, 2: 0.5}
        localizer, _ = self.scripted(places, memory, inliers, along, monkeypatch)
        result = localizer.localize(places[3].query)
        assert (result.keyframe_id, result.ahead_id) == (1, 3)
        # At the end of its path (6 is path a's last), the winner stays.
        localizer, _ = self.scripted(places, memory, {6: 40}, {6: 0.9}, monkeypatch)
        assert localizer.localize(places[6].query).ahead_id == 6

    @pytest.mark.parametrize(("change", "steps"), [
        ({"inliers": {4: 0}}, 3),      # the next key image towards the query is refused
        ({"along": {5: math.nan}}, 3),  # the winner's fit has no translation: it stands there
        ({}, 1),                        # one step finds no change of side
        ({}, 0),                        # the walk is off
    ])
    def test_without_a_bracketing_pair_the_winner_stays(
            self, places: list[Place], memory: VisualMemory, monkeypatch: pytest.MonkeyPatch,
            change: dict[str, dict[int, float]], steps: int) -> None:
        inliers = {**self.INLIERS, **change.get("inliers", {})}
        along = {**self.ALONG, **change.get("along", {})}
        localizer, _ = self.scripted(places, memory, inliers, along, monkeypatch, steps)
        result = localizer.localize(places[3].query)
        assert (result.keyframe_id, result.ahead_id) == (5, 5)

    def test_a_neighbour_without_translation_is_where_the_query_stands(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, _ = self.scripted(places, memory, self.INLIERS,
                                     {**self.ALONG, 4: math.nan}, monkeypatch)
        result = localizer.localize(places[3].query)
        assert (result.keyframe_id, result.ahead_id) == (4, 4)


class TestOtherPaths:
    """Step 5: the view found on the other paths too, each walked as the winner is."""

    def scripted(self, places: list[Place], memory: VisualMemory, inliers: dict[int, int],
                 along: dict[int, float], monkeypatch: pytest.MonkeyPatch
                 ) -> tuple[Localizer, list[int]]:
        config = dataclasses.replace(CONFIG, candidates=len(places))
        return scripted_localizer(memory, config, inliers, along, monkeypatch)

    # Path "a" holds key images 0-6, path "b" 7-11. The query lies between a's 3 and 4,
    # and between b's 9 and 10 (nearer 9).
    INLIERS: ClassVar[dict[int, int]] = {3: 30, 4: 35, 9: 25, 10: 20}
    ALONG: ClassVar[dict[int, float]] = {3: 0.2, 4: -0.6, 9: 0.3, 10: -0.4}

    def test_each_other_path_is_walked_from_its_most_matched_candidate(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, verified = self.scripted(places, memory, self.INLIERS, self.ALONG,
                                            monkeypatch)
        result = localizer.localize(places[3].query, each_path=True)
        assert (result.keyframe_id, result.ahead_id) == (3, 4)
        assert result.elsewhere == ((9, 10),)
        assert verified[-2:] == [9, 10]

    def test_only_on_request_and_only_accepted(
            self, places: list[Place], memory: VisualMemory,
            monkeypatch: pytest.MonkeyPatch) -> None:
        localizer, verified = self.scripted(places, memory, self.INLIERS, self.ALONG,
                                            monkeypatch)
        assert localizer.localize(places[3].query).elsewhere == ()
        assert 9 not in verified
        refused = {3: 30, 4: 35}  # path b's candidates refused
        localizer, _ = self.scripted(places, memory, refused, self.ALONG, monkeypatch)
        assert localizer.localize(places[3].query, each_path=True).elsewhere == ()
