from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from shared.errors import MemoryFormatError, UnknownKeyframeError
from shared.memory import EdgeKind, Junction, VisualMemory, VisualPath
from tests.shared.memory.builders import loop_memory, make_record, make_records, small_camera


class TestAddPath:
    def test_assigns_ids_indexes_and_relative_distances(self, rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        records = make_records(rng, memory.camera, [0.5, 0.25])
        records = [replace(r, distance_m=r.distance_m + 10.0) for r in records]
        first = memory.add_path("corridor", records)
        second = memory.add_path("hall", make_records(rng, memory.camera, [1.0], t0_ns=5))
        assert (first.id, first.keyframe_ids) == (0, (0, 1, 2))
        assert (second.id, second.keyframe_ids) == (1, (3, 4))
        assert [memory.keyframes[i].distance_m for i in first.keyframe_ids] == [0.0, 0.5, 0.75]
        assert [(k.path_id, k.index) for k in memory.keyframes.values()] == [
            (0, 0), (0, 1), (0, 2), (1, 0), (1, 1)
        ]
        assert memory.keyframes[4].thumbnail.shape == (60, 80)

    def test_views_are_read_only(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        with pytest.raises(TypeError):
            memory.keyframes[99] = memory.keyframes[0]  # type: ignore[index]

    @pytest.mark.parametrize(
        ("change", "fragment"),
        [
            ({"image": np.zeros((240, 320), np.uint8)}, "image is 320x240 px but the camera"),
            ({"t_ns": 0}, "t_ns 0 is not after the previous key image's 1000000000"),
            ({"distance_m": 0.1}, "distance_m 0.1 m is less than the previous key image's 0.5 m"),
            ({"patches": np.zeros((12, 9), np.float32)}, "descriptors have 9 values"),
            ({"tracked_from_previous": np.array([[12, 0]])},
             "tracked_from_previous: corner 12 of the previous key image, which has 12"),
        ],
    )
    def test_bad_record_leaves_memory_unchanged(
        self, rng: np.random.Generator, change: dict[str, object], fragment: str
    ) -> None:
        memory = loop_memory(rng)
        records = make_records(rng, memory.camera, [0.5, 0.5])
        records[2] = replace(records[2], **change)
        with pytest.raises(MemoryFormatError, match=fragment):
            memory.add_path("bad", records)
        assert len(memory.keyframes) == 7 and len(memory.paths) == 2
        assert memory.add_path("good", records[:2]).keyframe_ids == (7, 8)

    def test_keeps_the_tracks_and_refuses_them_on_a_first_key_image(
        self, rng: np.random.Generator
    ) -> None:
        memory = VisualMemory(small_camera())
        records = make_records(rng, memory.camera, [0.5, 0.5])
        path = memory.add_path("corridor", records)
        for keyframe_id, record in zip(path.keyframe_ids, records, strict=True):
            np.testing.assert_array_equal(
                memory.keyframes[keyframe_id].tracked_from_previous, record.tracked_from_previous
            )
        with pytest.raises(MemoryFormatError, match="must have no tracked_from_previous"):
            memory.add_path("starts tracked", records[1:])

    def test_no_records(self) -> None:
        with pytest.raises(MemoryFormatError, match="has no key images"):
            VisualMemory(small_camera()).add_path("empty", [])


class TestJunctions:
    def test_unknown_id(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        with pytest.raises(UnknownKeyframeError, match="no key image with id 42"):
            memory.add_junction(Junction(1, 42, 10))

    def test_a_pair_is_joined_once_in_either_direction(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        with pytest.raises(MemoryFormatError, match="already joined"):
            memory.add_junction(Junction(4, 3, 99))

    def test_edges_both_ways(self, rng: np.random.Generator) -> None:
        edges = {(e.from_id, e.to_id): e for e in loop_memory(rng).edges()}
        assert edges[(3, 4)].kind is edges[(4, 3)].kind is EdgeKind.JUNCTION
        assert edges[(3, 4)].length_m == 0.0
        assert edges[(4, 5)].kind is EdgeKind.PATH and edges[(4, 5)].length_m == 1.0
        assert (5, 4) not in edges  # a path is followed in teach direction only
        assert len(edges) == 3 + 2 + 2 * 2


class TestPlanRoute:
    def test_along_one_path(self, rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 0.5]))
        assert memory.plan_route(0, 3) == [0, 1, 2, 3]
        assert memory.plan_route(2, 2) == [2]
        assert memory.plan_route(3, 0) == []  # paths are directed

    def test_across_junctions(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        assert memory.plan_route(1, 5) == [1, 2, 3, 4, 5]
        assert memory.plan_route(5, 2) == [5, 6, 0, 1, 2]
        assert memory.plan_route(4, 3) == [4, 3]

    def test_takes_the_shorter_of_two_routes(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        # A shortcut from corridor key image 1 to "back" key image 5: 0.4 m instead of 2 m.
        shortcut = memory.add_path("shortcut", make_records(rng, memory.camera, [0.2, 0.2]))
        memory.add_junction(Junction(1, shortcut.keyframe_ids[0], 50))
        memory.add_junction(Junction(shortcut.keyframe_ids[-1], 5, 50))
        assert memory.plan_route(0, 5) == [0, 1, *shortcut.keyframe_ids, 5]
        assert memory.plan_route(2, 5) == [2, 3, 4, 5]

    def test_from_several_starts_the_shortest_route_wins(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        # Corridor 0-3, "back" 4-6, junctions 3 <-> 4 and 6 <-> 0: from 2 or 5 to 6.
        assert memory.plan_route_from([2, 5], 6) == [5, 6]
        assert memory.plan_route_from([5, 2], 1) == [5, 6, 0, 1]
        # Equal lengths: the first start. Junctions are zero-length, so 3 and 4 tie.
        assert memory.plan_route_from([4, 3], 5) == [4, 5]
        assert memory.plan_route_from([3, 4], 5) == [3, 4, 5]
        assert memory.plan_route_from([6, 1], 6) == [6]

    def test_from_several_starts_none_reaching_is_no_route(self,
                                                           rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 0.5]))
        assert memory.plan_route_from([3, 2], 1) == []
        assert memory.plan_route_from([], 1) == []
        assert memory.plan_route_from([3, 0], 1) == [0, 1]
        with pytest.raises(UnknownKeyframeError, match="99"):
            memory.plan_route_from([0, 99], 1)

    def test_key_images_within_a_radius_either_way(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        # Corridor 0-3 (0.5 m steps), "back" 4-6 (1 m steps), junctions 3 <-> 4 and 6 <-> 0.
        assert memory.within(2, 0.6) == {1, 2, 3, 4}  # 4 is 3 across a junction
        assert memory.within(3, 1.0) == {1, 2, 3, 4, 5}  # across a junction, both ways
        assert memory.within(0, 0.0) == {0, 6}
        with pytest.raises(UnknownKeyframeError, match="99"):
            memory.within(99, 1.0)

    @pytest.mark.parametrize(("start", "goal"), [(99, 0), (0, 99)])
    def test_unknown_id_is_named(self, rng: np.random.Generator, start: int, goal: int) -> None:
        with pytest.raises(UnknownKeyframeError, match="no key image with id 99") as error:
            loop_memory(rng).plan_route(start, goal)
        assert error.value.keyframe_id == 99
        assert isinstance(error.value, LookupError)


class TestConnectivity:
    def test_loop_is_strongly_connected(self, rng: np.random.Generator) -> None:
        report = loop_memory(rng).connectivity()
        assert report.strongly_connected
        assert report.components == ((0, 1, 2, 3, 4, 5, 6),)
        assert report.unreachable == ()

    def test_single_path_names_what_cannot_come_back(self, rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        memory.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 0.5]))
        report = memory.connectivity()
        assert not report.strongly_connected
        assert report.components == ((0,), (1,), (2,), (3,))
        assert report.not_reachable_from_main == ()
        assert report.cannot_reach_main == (1, 2, 3)
        assert memory.unreachable_from(2) == (0, 1)
        assert memory.unreachable_from(0) == ()

    def test_spur_and_island(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        spur = memory.add_path("spur", make_records(rng, memory.camera, [0.5, 0.5]))  # 7, 8, 9
        memory.add_junction(Junction(spur.keyframe_ids[0], 2, 60))
        island = memory.add_path("island", make_records(rng, memory.camera, [0.5]))  # 10, 11
        report = memory.connectivity()
        assert not report.strongly_connected
        assert report.components[0] == (0, 1, 2, 3, 4, 5, 6, 7)
        assert report.cannot_reach_main == (8, 9, *island.keyframe_ids)
        assert report.not_reachable_from_main == island.keyframe_ids
        assert report.unreachable == (8, 9, 10, 11)
        assert memory.plan_route(0, 9) == [0, 1, 2, 7, 8, 9]
        assert memory.plan_route(9, 0) == []

    def test_empty_memory(self) -> None:
        report = VisualMemory(small_camera()).connectivity()
        assert report.strongly_connected and report.components == ()


class TestFromParts:
    def test_rebuilds_an_equal_memory(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        again = VisualMemory.from_parts(
            memory.camera, memory.keyframes.values(), memory.paths.values(), memory.junctions
        )
        assert again.paths == memory.paths and again.junctions == memory.junctions
        assert again.plan_route(5, 2) == [5, 6, 0, 1, 2]

    def test_dangling_and_duplicate_ids(self, rng: np.random.Generator) -> None:
        memory = loop_memory(rng)
        keyframes = list(memory.keyframes.values())
        paths = list(memory.paths.values())
        cases = [
            ([*keyframes, keyframes[2]], paths, [], "key image 2: duplicate key image id"),
            (keyframes, [*paths, VisualPath(2, "ghost", (17,))], [], "lists key image 17"),
            (keyframes, paths[:1], [], "key image 4: says it is on path 1, which does not list"),
            (keyframes, paths, [Junction(3, 70, 5)], "key image 70 does not exist"),
            (keyframes, [paths[0], VisualPath(1, "back", (4, 6, 5))], [], "as key image 1"),
        ]
        for kfs, ps, js, fragment in cases:
            with pytest.raises(MemoryFormatError, match=fragment):
                VisualMemory.from_parts(memory.camera, kfs, ps, js)


# -- property: random multigraphs ---------------------------------------------------------------

_CAMERA = small_camera(16, 12)
_RECORD = make_record(np.random.default_rng(0), _CAMERA, 0, 0.0, n_features=2)


@st.composite
def random_memories(draw: st.DrawFn) -> VisualMemory:
    memory = VisualMemory(_CAMERA)
    for p in range(draw(st.integers(1, 5))):
        steps = draw(st.lists(st.sampled_from([0.0, 0.25, 0.5, 1.0, 2.0]), min_size=1, max_size=4))
        distances = np.concatenate([[0.0], np.cumsum(steps)])
        records = [
            replace(_RECORD, t_ns=p * 100 + i, distance_m=float(d)) for i, d in enumerate(distances)
        ]
        memory.add_path(f"path {p}", records)
    ids = sorted(memory.keyframes)
    pairs = draw(st.lists(st.tuples(st.sampled_from(ids), st.sampled_from(ids)), max_size=12))
    for a, b in pairs:
        if a != b and all(j.pair != {a, b} for j in memory.junctions):
            memory.add_junction(Junction(a, b, 30))
    return memory


def shortest_lengths_m(memory: VisualMemory, start: int) -> dict[int, float]:
    """Bellman-Ford over memory.edges(): the reference the planner must match."""
    best = dict.fromkeys(memory.keyframes, math.inf)
    best[start] = 0.0
    for _ in range(len(best)):
        for e in memory.edges():
            best[e.to_id] = min(best[e.to_id], best[e.from_id] + e.length_m)
    return best


@settings(max_examples=60, deadline=None)
@given(memory=random_memories(), data=st.data())
def test_plan_route_is_a_shortest_walk_along_edges(
    memory: VisualMemory, data: st.DataObject
) -> None:
    ids = sorted(memory.keyframes)
    start = data.draw(st.sampled_from(ids))
    goal = ids[(ids.index(start) + data.draw(st.integers(1, len(ids) - 1))) % len(ids)]
    route = memory.plan_route(start, goal)
    lengths = {(e.from_id, e.to_id): e.length_m for e in memory.edges()}
    best = shortest_lengths_m(memory, start)
    event("unreachable" if math.isinf(best[goal]) else f"route of {len(route)} key images")
    if math.isinf(best[goal]):
        assert route == []
        assert goal in memory.unreachable_from(start)
        assert not memory.connectivity().strongly_connected
        return
    assert route[0] == start and route[-1] == goal
    assert len(set(route)) == len(route)
    steps = list(itertools.pairwise(route))
    assert all(step in lengths for step in steps)
    assert math.isclose(sum(lengths[s] for s in steps), best[goal], abs_tol=1e-9)
    assert goal not in memory.unreachable_from(start)
