"""Joining a new path to the memory (robot/memory/junctions.py) on textured synthetic places."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import LocalizeConfig
from robot.memory.junctions import (
    JunctionAttempt,
    JunctionOutcome,
    _largest_consistent,
    junction_attempts,
    same_place,
)
from shared.config import CameraMountConfig
from shared.memory import Junction, VisualMemory
from tests.robot.memory.textured import FEATURES, Place, make_places, memory_of, record_of
from tests.shared.memory.builders import make_records, shared_stretch_memory, small_camera

CONFIG = LocalizeConfig(candidates=4, min_inliers=10)
MIN_MATCHES = 20  # the synthetic places share at most 15 chance matches
MOUNT = CameraMountConfig()


@pytest.fixture(scope="module")
def places() -> list[Place]:
    return make_places(np.random.default_rng(5), 6, small_camera())


def attempts_of(memory: VisualMemory, path_id: int) -> list[JunctionAttempt]:
    return junction_attempts(memory, path_id, MOUNT, FEATURES, CONFIG, MIN_MATCHES)


def accepted_pairs(attempts: list[JunctionAttempt]) -> list[set[int]]:
    return [{a.end_id, a.best_id} for a in attempts if a.accepted]


class TestJunctionAttempts:
    def test_a_path_starting_where_another_ends_joins_it(self, places: list[Place]) -> None:
        # Path a: places 0, 1, 2 (ids 0-2). Path b starts at place 2, seen again (ids 3-5).
        memory = memory_of(
            {
                "a": [places[0].key_image, places[1].key_image, places[2].key_image],
                "b": [places[2].query, places[3].key_image, places[4].key_image],
            }
        )
        attempts = attempts_of(memory, 1)
        # b's ends 3 and 5 among path a, then a's ends 0 and 2 along path b.
        assert [a.end_id for a in attempts] == [3, 5, 0, 2]
        assert attempts[0].best_id == 2 and attempts[0].matches >= MIN_MATCHES
        assert attempts[3].best_id == 3 and attempts[3].matches >= MIN_MATCHES
        # The same place found both ways makes one junction.
        assert accepted_pairs(attempts) == [{2, 3}]
        assert [a.outcome for a in attempts] == [
            JunctionOutcome.JOINED,
            JunctionOutcome.TOO_FEW_MATCHES,
            JunctionOutcome.TOO_FEW_MATCHES,
            JunctionOutcome.ALREADY_JOINED,
        ]

    def test_ends_are_preferred_to_the_best_match(self, places: list[Place]) -> None:
        # Path a's last two key images show place 2 (the last one noisier); b starts at
        # place 2 seen again, which matches a's last but one best.
        noisy = places[2].key_image + np.random.default_rng(1).normal(0.0, 6.0, (120, 160))
        memory = memory_of(
            {
                "a": [
                    places[0].key_image,
                    places[2].key_image,
                    np.clip(noisy, 0, 255).astype(np.uint8),
                ],
                "b": [places[2].query, places[5].key_image],
            }
        )
        attempts = attempts_of(memory, 1)
        assert (attempts[0].end_id, attempts[0].best_id) == (3, 1)  # the best match...
        assert (attempts[3].end_id, attempts[3].best_id) == (2, 3)
        assert attempts[0].matches > attempts[3].matches >= MIN_MATCHES
        # ...is not an end: a's end 2 joins b's start 3 instead, and 3 joins a only once.
        assert accepted_pairs(attempts) == [{2, 3}]

    def test_a_second_junction_the_odometry_contradicts_is_refused(
            self, places: list[Place]) -> None:
        # Path b starts where a ends (place 3) and ends where a starts (place 0), but
        # its odometry runs 1.5 m on ahead where a's runs 1.5 m back: two places a
        # pattern period apart in a corridor look like this. One junction stands.
        memory = memory_of(
            {
                "a": [places[i].key_image for i in range(4)],
                "b": [places[3].query, places[4].key_image, places[5].key_image,
                      places[0].query],
            }
        )
        attempts = attempts_of(memory, 1)
        ends = {(a.end_id, a.best_id) for a in attempts}
        assert {(4, 3), (7, 0)} <= ends
        assert len(accepted_pairs(attempts)) == 1
        assert accepted_pairs(attempts)[0] in ({3, 4}, {0, 7})
        assert JunctionOutcome.INCONSISTENT in {a.outcome for a in attempts}

    def test_a_junction_a_third_path_contradicts_is_refused(self) -> None:
        # Paths b and c each join a, 3.5 m apart along it (b at its start, c at its end),
        # and b's end looks like c's start: through that junction the two places would be
        # 1 m + 1 m apart. Each pair of paths has one junction, so
        # no pair can disagree; the triangle the three make cannot close.
        places = make_places(np.random.default_rng(8), 11, small_camera())
        memory = memory_of({"a": [places[i].key_image for i in range(8)],
                            "b": [places[0].query, places[8].key_image, places[9].key_image]})
        for attempt in attempts_of(memory, 1):
            if attempt.accepted:
                memory.add_junction(attempt.junction())
        assert [{j.from_id, j.to_id} for j in memory.junctions] == [{0, 8}]
        memory.add_path("c", [record_of(image, memory.camera, i) for i, image in enumerate(
            [places[9].query, places[10].key_image, places[7].query])])
        attempts = attempts_of(memory, 2)
        ends = {(a.end_id, a.best_id) for a in attempts}
        assert {(11, 10), (13, 7)} <= ends
        assert len(accepted_pairs(attempts)) == 1
        assert JunctionOutcome.INCONSISTENT in {a.outcome for a in attempts}

    def test_junctions_already_made_are_not_made_again(self, places: list[Place]) -> None:
        memory = memory_of(
            {"a": [places[0].key_image, places[1].key_image], "b": [places[1].query]}
        )
        for attempt in attempts_of(memory, 1):
            if attempt.accepted:
                memory.add_junction(attempt.junction())
        assert [{j.from_id, j.to_id} for j in memory.junctions] == [{1, 2}]
        again = attempts_of(memory, 1)
        assert again and not any(a.accepted for a in again)
        assert JunctionOutcome.ALREADY_JOINED in {a.outcome for a in again}
        with pytest.raises(ValueError, match="was not accepted"):
            again[0].junction()

    def test_a_lone_path_has_nothing_to_join(self, places: list[Place]) -> None:
        memory = memory_of({"a": [places[0].key_image, places[1].key_image]})
        assert attempts_of(memory, 0) == []
        with pytest.raises(KeyError):
            attempts_of(memory, 7)


class TestSamePlace:
    """Key images of two paths at one place, judged by the junctions between the paths."""

    @pytest.fixture
    def memory(self) -> VisualMemory:
        return shared_stretch_memory(np.random.default_rng(3))

    def test_equally_far_from_the_junction_on_both_paths(self, memory: VisualMemory) -> None:
        assert same_place(memory, 6, 17, 45.0)  # both 2 m past the junction
        assert same_place(memory, 17, 6, 45.0)
        assert same_place(memory, 6, 16, 45.0)  # one key image (0.5 m) off: odometry's slack

    def test_a_look_alike_metres_away_is_not(self, memory: VisualMemory) -> None:
        assert not same_place(memory, 12, 17, 45.0)  # 5 m and 2 m past it: a pattern period
        # 3 m apart: within the allowance of a turn of 45 degrees between the paths' frames
        # at the junction, not within the odometry's slack along them.
        assert not same_place(memory, 8, 13, 45.0)

    def test_one_path_or_paths_no_junction_joins_are_never_one_place(
            self, memory: VisualMemory) -> None:
        rng = np.random.default_rng(4)
        memory.add_path("apart", make_records(rng, memory.camera, [0.5] * 4, t0_ns=10**12))
        assert not same_place(memory, 4, 6, 45.0)
        assert not same_place(memory, 6, 24, 45.0)


class TestLargestConsistentSet:
    """Of a new path's junctions, the most that agree win, not the first tried."""

    @pytest.fixture
    def memory(self) -> VisualMemory:
        rng = np.random.default_rng(6)
        memory = VisualMemory(small_camera())
        # A corridor, 8 m (ids 0-16); a path along it from its 3 m to its 7 m (17-25).
        memory.add_path("corridor", make_records(rng, memory.camera, [0.5] * 16))
        memory.add_path("along", make_records(rng, memory.camera, [0.5] * 8, t0_ns=10**11))
        return memory

    def test_two_that_agree_beat_a_look_alike_tried_first(self, memory: VisualMemory) -> None:
        # Tried first (two path ends): the corridor's start looks like the path's start,
        # 3 m away. The path's two true junctions, in the corridor's middle, come after.
        look_alike, start, end = (0, 17, 0.05), (17, 6, 0.05), (25, 14, 0.05)
        assert _largest_consistent(memory, [look_alike, start, end], [], set()) == [1, 2]

    def test_of_equally_large_sets_the_first_tried(self, memory: VisualMemory) -> None:
        # The two starts reuse a link (the path's start joins the corridor once).
        assert _largest_consistent(memory, [(0, 17, 0.05), (17, 6, 0.05)], [], set()) == [0]
        assert _largest_consistent(memory, [(17, 6, 0.05), (0, 17, 0.05)], [], set()) == [0]
        assert _largest_consistent(memory, [], [], set()) == []

    def test_junctions_already_made_bind_the_choice(self, memory: VisualMemory) -> None:
        memory.add_junction(Junction(from_id=0, to_id=17, matches=50))
        joined = [(0, 17, math.radians(45.0))]
        links = {(0, 1), (17, 0)}
        # The path's start has joined the corridor: it cannot again. Its end is judged
        # against that junction, allowed 45 degrees between its views (not recorded): 3 m
        # off at 7 m from it passes.
        assert _largest_consistent(memory, [(17, 6, 0.05), (25, 14, 0.05)], joined, links) == [1]
