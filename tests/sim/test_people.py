from __future__ import annotations

import numpy as np
import pytest

from shared.errors import ConfigError
from shared.pose import Pose2
from sim._geometry import point_segment_distances, points_in_polygons
from sim.config import PeopleConfig, SimConfig
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.people import SIDESTEP_MARGIN_M
from sim.simulation import Simulation
from sim.world import World, load_world
from tests.sim.rooms import box_room


def people_sim(
    world: World, count: int, seed: int = 1, speed: float = 1.0, avoid_robot: bool = True
) -> Simulation:
    people = PeopleConfig(count=count, speed_m_s=speed, avoid_robot=avoid_robot)
    config = SimConfig(seed=seed, landmark_density_scale=0.0, people=people)
    return Simulation(world, config)


def gap_to_robot(sim: Simulation) -> float:
    """Distance between person 0's body and the robot's box, m (negative: overlapping)."""
    person = tuple(sim.people.positions()[0])
    return sim.body.shape.point_query(person).distance - sim.config.people.radius_m


class TestWalking:
    def test_people_never_cross_walls_or_furniture_over_a_long_run(self) -> None:
        world = load_world("lab")
        sim = people_sim(world, count=5, seed=7)
        track = []
        for _ in range(6000):  # 60 s
            sim.step()
            track.append(sim.people.positions())
        positions = np.array(track)  # (T, M, 2)
        flat = positions.reshape(-1, 2)
        radius = sim.config.people.radius_m
        a = np.array([w.start for w in world.walls])
        b = np.array([w.end for w in world.walls])
        wall_gap = point_segment_distances(flat, a, b).min(axis=1) - WALL_HALF_THICKNESS_M
        assert wall_gap.min() >= radius - 1e-6
        assert not points_in_polygons(flat, world.furniture_corners()).any()
        assert sim.free_space.is_reachable(flat).all()
        # Steps are short (no teleporting through a wall): at most speed * dt.
        steps = np.linalg.norm(np.diff(positions, axis=0), axis=2)
        assert steps.max() <= 1.0 * 0.01 + 1e-9
        # They walk a lot and pause sometimes.
        assert steps.sum(axis=0).min() > 10.0
        assert (steps == 0).mean() > 0.01

    def test_same_seed_same_walks_other_seed_other_walks(self) -> None:
        world = box_room()

        def walk(seed: int) -> np.ndarray:
            sim = people_sim(world, count=3, seed=seed)
            sim.step_until(2_000_000_000)
            return sim.people.positions()

        assert np.array_equal(walk(1), walk(1))
        assert not np.array_equal(walk(1), walk(2))

    def test_people_start_away_from_the_robot(self) -> None:
        sim = people_sim(box_room(), count=4)
        positions, radius, height = sim.people_state()
        assert positions.shape == (4, 2)
        assert (radius, height) == (0.25, 1.75)
        assert np.linalg.norm(positions - [5.0, 3.0], axis=1).min() >= 1.5

    def test_placing_the_robot_by_a_person_moves_that_person_away(self) -> None:
        sim = people_sim(box_room(), count=4)
        before = sim.people.positions().copy()
        x, y = before[2]
        sim.place_robot(Pose2(float(x), float(y), 0.0))
        after = sim.people.positions()
        assert np.linalg.norm(after - [x, y], axis=1).min() >= 1.5
        moved = np.linalg.norm(after - before, axis=1) > 0
        far = np.linalg.norm(before - [x, y], axis=1) >= 1.5
        assert moved[2] and not moved[far].any()  # only those too close moved

    def test_too_many_people_for_the_world(self) -> None:
        with pytest.raises(ConfigError, match=r"^people: cannot place 40 people"):
            people_sim(box_room((4.0, 3.0)), count=40)


class TestBumping:
    def test_a_person_walking_into_the_robot_bumps_and_pushes_it(self) -> None:
        sim = people_sim(box_room(), count=1, avoid_robot=False)
        sim.people.place(0, (8.0, 3.0), (2.0, 3.0))  # straight at the robot's front
        bumped = []
        for _ in range(400):
            sim.step()
            bumped.append(sim.body.bumped_front)
        assert any(bumped) and not sim.body.bumped_rear
        assert sim.body.pose_w[0] < 5.0  # pushed back
        # The person stopped on contact, then walked off: no longer touching the robot.
        assert not bumped[-1]
        assert np.linalg.norm(sim.people.positions()[0] - sim.body.pose_w[:2]) > 0.5

    def test_the_robot_driving_into_a_standing_person_stalls(self) -> None:
        sim = people_sim(box_room(), count=1, speed=0.0, avoid_robot=False)
        sim.people.place(0, (6.5, 3.0), (6.5, 3.0))
        sim.body.command(0.3, 0.0)
        sim.step_until(4_000_000_000)
        assert sim.body.bumped_front and sim.body.stalled
        assert sim.body.pose_w[0] == pytest.approx(
            6.5 - 0.25 - sim.config.body.length_m / 2, abs=0.01
        )


class TestYielding:
    def test_a_person_walking_at_a_parked_robot_stops_short_waits_and_walks_off(self) -> None:
        sim = people_sim(box_room(), count=1)
        sim.people.place(0, (8.0, 3.0), (2.0, 3.0))  # straight at the robot's front
        track, gaps = [], []
        for _ in range(600):  # 6 s
            sim.step()
            track.append(sim.people.positions()[0])
            gaps.append(gap_to_robot(sim))
            assert not (sim.body.bumped_front or sim.body.bumped_rear)
        assert sim.body.pose_w[:2] == pytest.approx((5.0, 3.0), abs=1e-9)  # not pushed
        # Stopped within one walking step of the clearance...
        positions = np.array(track)
        stop = int(np.argmax(np.all(positions[1:] == positions[:-1], axis=1)))
        clearance, step_m = sim.config.people.clearance_m, 1.0 * 0.01
        assert clearance - step_m - 1e-9 <= gaps[stop] <= clearance
        # ...stood there for the patience, then walked off elsewhere.
        standing_s = np.all(positions == positions[stop], axis=1).sum() * 0.01
        assert standing_s == pytest.approx(sim.config.people.yield_patience_s, abs=0.03)
        assert np.linalg.norm(positions[-1] - positions[stop]) > 0.5

    def test_a_person_meeting_the_robot_head_on_steps_aside(self) -> None:
        sim = people_sim(box_room(), count=1)
        sim.people.place(0, (8.0, 3.0), (2.0, 3.0))
        sim.body.command(0.3, 0.0)
        gaps, track = [], []
        while sim.body.pose_w[0] < 7.0:  # they meet near x = 6.6
            sim.step()
            gaps.append(gap_to_robot(sim))
            track.append(sim.people.positions()[0])
            assert not (sim.body.bumped_front or sim.body.bumped_rear)
            assert sim.now_ns < 20_000_000_000
        assert not sim.body.stalled and min(gaps) > 0.5
        # Stepped square to the robot's path (to its left, x fixed), out to the robot's
        # half-diagonal plus body and margin.
        positions = np.array(track)
        first_aside = int(np.argmax(positions[:, 1] > 3.0))
        aside = positions[positions[:, 0] == positions[first_aside, 0]]
        half_diagonal = np.hypot(sim.config.body.length_m, sim.config.body.width_m) / 2
        reach = half_diagonal + sim.config.people.radius_m + SIDESTEP_MARGIN_M
        assert aside[:, 1].max() == pytest.approx(3.0 + reach, abs=1e-6)

    @pytest.mark.parametrize("seed", [1, 2, 3])
    def test_people_never_bump_a_robot_driving_circles(self, seed: int) -> None:
        sim = people_sim(box_room((6.0, 4.0)), count=4, seed=seed)
        sim.body.command(0.2, 0.3)
        for _ in range(3000):  # 30 s in a small room
            sim.step()
            assert not (sim.body.bumped_front or sim.body.bumped_rear)

    def test_without_avoid_robot_people_do_bump_a_robot_driving_circles(self) -> None:
        sim = people_sim(box_room((6.0, 4.0)), count=4, seed=1, avoid_robot=False)
        sim.body.command(0.2, 0.3)
        bumps = 0
        for _ in range(3000):
            sim.step()
            bumps += sim.body.bumped_front or sim.body.bumped_rear
        assert bumps > 0

    @pytest.mark.parametrize("tries", [1, 4])
    def test_in_a_2_m_corridor_a_person_steps_to_the_wall(self, tries: int,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
        # The lab's main corridor (y 9-11): too narrow for the full sidestep (the robot's
        # half-diagonal plus a margin on either side); flat against the wall is clear.
        monkeypatch.setattr("sim.people._SIDESTEP_TRIES", tries)
        sim = people_sim(load_world("lab"), count=1, speed=0.8)
        sim.place_robot(Pose2(8.0, 10.05, 0.0))
        sim.people.place(0, (11.5, 9.75), (4.0, 9.75))  # walking west, at the robot
        sim.body.command(0.2, 0.0)
        bumped = False
        for k in range(1, 100):
            sim.step_until(k * 100_000_000)
            bumped = bumped or sim.body.bumped_front or sim.body.bumped_rear
        assert bumped == (tries == 1)  # a single full-length try (the old rule) finds no room

    def test_same_seed_same_yields(self) -> None:
        def walk() -> np.ndarray:
            sim = people_sim(box_room((6.0, 4.0)), count=4, seed=4)
            sim.body.command(0.2, 0.3)
            sim.step_until(10_000_000_000)
            return sim.people.positions()

        assert np.array_equal(walk(), walk())

    @pytest.mark.parametrize(
        ("field", "value", "message"),
        [
            ("clearance_m", 0.0, "clearance_m must be > 0"),
            ("yield_patience_s", -1.0, "yield_patience_s must be >= 0"),
        ],
    )
    def test_bad_yield_settings(self, field: str, value: float, message: str) -> None:
        with pytest.raises(ValueError, match=message):
            PeopleConfig(**{field: value})
