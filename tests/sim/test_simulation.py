from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from shared.errors import ConfigError
from shared.pose import Pose2
from sim.config import OdometryConfig, PeopleConfig, SimConfig
from sim.simulation import OCCLUDER_FILTER, Simulation
from sim.world import load_world


@pytest.fixture(scope="module")
def lab():
    return load_world("lab")


def trajectory(sim: Simulation, seconds: float) -> np.ndarray:
    """Drive a fixed command pattern; rows of true pose, odometry and people positions."""
    rows = []
    for k in range(round(seconds * 100)):
        sim.body.command(0.5, 0.3 * math.sin(k / 50.0))
        sim.step()
        rows.append(
            np.concatenate([sim.body.pose_w, sim.body.odom_pose, sim.people.positions().ravel()])
        )
    return np.array(rows)


class TestDeterminism:
    def test_same_seed_same_run_other_seed_other_run(self, lab) -> None:
        config = SimConfig(seed=5, people=PeopleConfig(count=3))
        first = trajectory(Simulation(lab, config), 5.0)
        again = trajectory(Simulation(lab, config), 5.0)
        assert np.array_equal(first, again)
        other = trajectory(Simulation(lab, SimConfig(seed=6, people=PeopleConfig(count=3))), 5.0)
        assert not np.array_equal(first, other)

    def test_people_count_changes_neither_landmarks_nor_odometry(self, lab) -> None:
        # Standing people (speed 0) away from the robot: the robot's run is the same.
        alone = Simulation(lab, SimConfig(seed=5))
        crowded = Simulation(lab, SimConfig(seed=5, people=PeopleConfig(count=6, speed_m_s=0.0)))
        assert np.array_equal(alone.landmarks.positions_w, crowded.landmarks.positions_w)
        assert np.array_equal(alone.landmarks.textures, crowded.landmarks.textures)
        a, b = trajectory(alone, 1.0), trajectory(crowded, 1.0)
        assert np.array_equal(a[:, :6], b[:, :6])


class TestTime:
    def test_step_until_takes_fixed_steps_on_the_grid(self, lab) -> None:
        sim = Simulation(lab, SimConfig(physics_dt_ns=10_000_000, landmark_density_scale=0.0))
        assert sim.step_until(35_000_000) == 4
        assert sim.now_ns == 40_000_000
        assert sim.step_until(40_000_000) == 0
        assert sim.step_until(1_000_000_000) == 96
        assert sim.now_ns == 1_000_000_000

    def test_step_with_an_explicit_step(self, lab) -> None:
        sim = Simulation(lab, SimConfig(landmark_density_scale=0.0))
        sim.step(3_000_000)
        assert sim.now_ns == 3_000_000
        for bad in (0, -5, 1.5, True):
            with pytest.raises(ValueError, match="dt_ns must be a positive integer"):
                sim.step(bad)  # type: ignore[arg-type]


class TestQueriesForTheRenderer:
    def test_occluder_filter_sees_walls_furniture_and_people_not_the_robot(self, lab) -> None:
        sim = Simulation(lab, SimConfig(landmark_density_scale=0.0, people=PeopleConfig(count=1)))
        x, y, _ = sim.body.pose_w
        # Through the robot (2, 10) to the west outer wall: the wall, never the robot.
        hits = sim.space.segment_query((x + 1.0, y), (-1.0, y), 0.0, OCCLUDER_FILTER)
        assert [Simulation.occluder_height(h.shape) for h in hits] == [2.6]
        assert sim.space.segment_query(
            (x + 1.0, y), (x - 1.0, y), 0.0, pymunk.ShapeFilter()
        )  # the robot is there
        # A desk in S1 (center (2.0, 4.5), 0.75 m high).
        desk = sim.space.segment_query_first((2.0, 6.0), (2.0, 4.5), 0.0, OCCLUDER_FILTER)
        assert desk is not None and sim.occluder_height(desk.shape) == 0.75
        # A person.
        sim.people.place(0, (5.0, 10.0), (5.0, 10.0))
        person = sim.space.segment_query_first((x + 1.0, y), (6.0, 10.0), 0.0, OCCLUDER_FILTER)
        assert (
            person is not None
            and sim.is_person(person.shape)
            and sim.occluder_height(person.shape) == 1.75
        )
        assert not sim.is_person(desk.shape)
        positions, radius, height = sim.people_state()
        assert positions.tolist() == [[5.0, 10.0]] and (radius, height) == (0.25, 1.75)

    def test_occluder_height_refuses_foreign_shapes(self) -> None:
        with pytest.raises(ValueError, match="not a simulation shape"):
            Simulation.occluder_height(pymunk.Circle(None, 1.0))


class TestPlaceRobot:
    def test_place_restarts_odometry_at_the_new_pose(self, lab) -> None:
        sim = Simulation(lab, SimConfig(landmark_density_scale=0.0, odometry=OdometryConfig()))
        trajectory(sim, 1.0)
        sim.place_robot(Pose2(20.0, 10.0, math.radians(180.0)))
        assert sim.body.pose_w == pytest.approx((20.0, 10.0, -math.pi))
        assert sim.body.odom_pose == (0.0, 0.0, 0.0) and sim.body.odom_distance_m == 0.0

    def test_place_into_a_wall_is_refused_and_changes_nothing(self, lab) -> None:
        sim = Simulation(lab, SimConfig(landmark_density_scale=0.0))
        trajectory(sim, 1.0)
        before = (sim.body.pose_w, sim.body.odom_pose)
        with pytest.raises(
            ConfigError, match=r"^robot pose: \(12.0, 9.1, 0.0 deg\) overlaps a wall"
        ):
            sim.place_robot(Pose2(12.0, 9.1, 0.0))
        with pytest.raises(ConfigError, match="overlaps a furniture"):
            sim.place_robot(Pose2(2.0, 4.5, 0.0))
        assert (sim.body.pose_w, sim.body.odom_pose) == before
