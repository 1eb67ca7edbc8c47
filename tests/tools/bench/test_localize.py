"""Localization in a memory taught in the simulator (tools/bench/localize.py), small and fast.

The full measurement (three lab routes, 200 queries, 300/3000 key image timings)
is ``python -m tools.bench.localize``; here one 2.5 m route and a dozen queries.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import VmnavConfig
from robot.memory import Localizer
from shared.camera_model import CameraModel
from shared.errors import InputError
from shared.memory import VisualMemory
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.world import World, load_world
from tests.shared.memory.builders import make_records, small_camera
from tests.tools.short_routes import write_short_routes_world
from tools.bench.localize import (
    acceptable_answers,
    accepted_answers,
    nearest_keyframe,
    rate_summary,
    relit_summary,
    run_queries,
    sample_query_pose,
    timing_summary,
)
from tools.harness.teach import TaughtMemory, teach_memory

CONFIG = VmnavConfig()


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> World:
    return load_world(write_short_routes_world(tmp_path_factory.mktemp("world")))


@pytest.fixture(scope="module")
def taught(world: World) -> TaughtMemory:
    return teach_memory(world, ["east_a"], CONFIG, SimConfig(), CameraModel.default(),
                        join=False)


@pytest.mark.slow
def test_random_views_near_the_path_find_the_nearest_key_image(
    world: World, taught: TaughtMemory
) -> None:
    sim = Simulation(world, SimConfig())
    renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
    localizer = Localizer.from_memory(taught.memory, CONFIG.camera.mount, CONFIG.features,
                                      CONFIG.localize)
    outcomes = run_queries(taught, localizer, sim, renderer, 12, np.random.default_rng(4))
    summary = rate_summary(outcomes)
    assert summary["localize_queries"] == 12
    assert summary["localize_top1_rate"] == 1.0, summary["failures"]
    assert all(o.result.ok for o in outcomes)


@pytest.mark.slow
class TestGroundTruth:
    def test_query_poses_stay_within_the_offsets(self, taught: TaughtMemory) -> None:
        rng = np.random.default_rng(0)
        for _ in range(200):
            x, y, yaw = sample_query_pose(taught, rng, 0.3, 15.0)
            # east_a runs along y = 10 heading +x, give or take the driver's wander.
            assert abs(y - 10.0) <= 0.3 + 0.05
            assert abs(math.degrees(yaw)) <= 15.0 + 3.0
            assert 1.9 <= x <= 4.6

    def test_nearest_and_its_neighbours(self, taught: TaughtMemory) -> None:
        ids = taught.memory.paths[0].keyframe_ids
        x, y, yaw = taught.true_poses[ids[2]]
        assert nearest_keyframe(taught, (x + 0.01, y + 0.2, yaw)) == ids[2]
        # Facing back along the path, no key image heads within 45 degrees: nearest of all.
        assert nearest_keyframe(taught, (x + 0.01, y + 0.2, yaw + math.pi)) == ids[2]
        assert accepted_answers(taught.memory, ids[2]) == {ids[1], ids[2], ids[3]}
        assert accepted_answers(taught.memory, ids[0]) == {ids[0], ids[1]}


def test_where_paths_overlap_the_other_paths_key_image_at_the_place_is_right(
    rng: np.random.Generator,
) -> None:
    memory = VisualMemory(small_camera())
    true_poses = {}
    # A along y = 0 every 0.5 m; B 5 cm beside it, 10 cm ahead; C along A backwards;
    # D parallel to A but 3 m away.
    paths = (
        ("A", [0.0, 0.5, 1.0, 1.5], 0.0, 0.0),
        ("B", [0.1, 0.6, 1.1], 0.05, 0.0),
        ("C", [1.5, 1.0, 0.5, 0.0], 0.0, math.pi),
        ("D", [0.0, 0.5], 3.0, 0.0),
    )
    for name, xs, y, yaw in paths:
        path = memory.add_path(name, make_records(rng, memory.camera, [0.5] * (len(xs) - 1)))
        true_poses.update({i: (x, y, yaw) for i, x in zip(path.keyframe_ids, xs, strict=True)})
    taught = TaughtMemory(memory, true_poses, tuple(memory.paths), (), reused=False)
    a, b = memory.paths[0].keyframe_ids, memory.paths[1].keyframe_ids
    # Nearest A1 (2 cm); its neighbours A0, A2 are up to 0.52 m away, so B0 (0.42 m) and
    # B1 (8 cm) are as good; B2 (0.58 m), C (backwards) and D (3 m) are not.
    assert acceptable_answers(taught, (0.52, 0.0, 0.0)) == {a[0], a[1], a[2], b[0], b[1]}


@pytest.mark.slow
def test_timing_summary_has_the_benchmark_keys(taught: TaughtMemory, world: World) -> None:
    sim = Simulation(world, SimConfig())
    image = FisheyeRenderer.for_simulation(sim, CameraModel.default()).render(sim).image
    summary = timing_summary(taught.memory, [image], CONFIG, sizes=(8, 16), exhaustive_queries=1)
    assert set(summary) == {
        f"localize_{kind}_{size}"
        for kind in ("ms", "exhaustive_ms", "speedup")
        for size in (8, 16)
    } | {"localize_speedup_vs_exhaustive"}
    assert summary["localize_speedup_vs_exhaustive"] == summary["localize_speedup_8"] > 0


@pytest.mark.slow
class TestRelit:
    def test_the_same_views_with_half_the_light(self, taught: TaughtMemory, world: World) -> None:
        localizer = Localizer.from_memory(taught.memory, CONFIG.camera.mount, CONFIG.features,
                                          CONFIG.localize)
        relit = relit_summary(taught, world, localizer, SimConfig(), CameraModel.default(), 8, 4,
                              "scale=0.5")
        assert relit["localize_relit"] == "scale=0.5"
        assert relit["localize_relit_top1_rate"] == 1.0, relit["localize_relit_failures"]
        assert relit["localize_relit_wrong_accepted"] == 0

    @pytest.mark.parametrize(("lighting", "message"), [
        ("dusk=1", "--lighting: unknown change"),
        ("scale=1000", "--lighting: light scale 1000"),
    ])
    def test_a_bad_lighting_change_is_one_line(
        self, taught: TaughtMemory, world: World, lighting: str, message: str
    ) -> None:
        localizer = Localizer.from_memory(taught.memory, CONFIG.camera.mount, CONFIG.features,
                                          CONFIG.localize)
        with pytest.raises(InputError, match=message):
            relit_summary(taught, world, localizer, SimConfig(), CameraModel.default(), 2, 0,
                          lighting)
