"""The sonar ring's pings (sim.pioneer.sonar rules 2-5) against real pymunk worlds."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
import pytest

from shared.aria import Command
from shared.aria.p3at import SONAR_POSES
from shared.pose import Pose2
from sim.config import EmulatorConfig, PeopleConfig, SimConfig
from sim.decor import PlacedObject
from sim.free_space import WALL_HALF_THICKNESS_M
from sim.pioneer.sonar import SonarRing
from sim.simulation import Simulation
from tests.sim.pioneer.rig import Rig
from tests.sim.rooms import box_room

QUIET = EmulatorConfig(sonar_noise_m=0.0)
ONE_RAY = EmulatorConfig(sonar_noise_m=0.0, sonar_rays=1)


def room(pose: Pose2) -> Simulation:
    """The bare 12 x 6 m room, the robot at ``pose``."""
    sim = Simulation(box_room((12.0, 6.0)), SimConfig())
    sim.place_robot(pose)
    return sim


def ping(sim: Simulation, number: int, config: EmulatorConfig = QUIET) -> float:
    """One noise-free ping of sonar ``number`` from the robot's true pose, m."""
    ring = SonarRing(sim.space, config, np.random.default_rng(0))
    return ring.range_m(number, sim.body.pose_w)


def transducer_w(sim: Simulation, number: int) -> tuple[float, float, float]:
    """Sonar ``number``'s position (m) and axis (rad), world frame."""
    x, y, yaw = sim.body.pose_w
    sx, sy, heading = SONAR_POSES[number]
    return (x + math.cos(yaw) * sx - math.sin(yaw) * sy,
            y + math.sin(yaw) * sx + math.cos(yaw) * sy, yaw + heading)


def post_at(sim: Simulation, number: int, distance_m: float, off_axis_deg: float) -> None:
    """A 10 cm square post ``distance_m`` from sonar ``number``, ``off_axis_deg`` off its
    axis, a face turned to the transducer (normal incidence)."""
    x, y, axis = transducer_w(sim, number)
    bearing = axis + math.radians(off_axis_deg)
    centre = (x + (distance_m + 0.05) * math.cos(bearing),
              y + (distance_m + 0.05) * math.sin(bearing))
    sim.add_object(PlacedObject("box", centre, (0.1, 0.1), 1.0, yaw_deg=math.degrees(bearing)))


class TestCone:
    def test_an_obstacle_10_deg_off_the_axis_is_seen_by_the_cone_not_by_one_ray(self) -> None:
        sim = room(Pose2(4.0, 3.0, 0.0))
        far_wall = ping(sim, 3, ONE_RAY)
        post_at(sim, 3, 1.5, 10.0)
        assert ping(sim, 3, ONE_RAY) == pytest.approx(far_wall)  # the axis passes it by
        assert ping(sim, 3) == pytest.approx(1.5, abs=0.005)  # the cone's ray at 10 deg

    def test_an_obstacle_outside_the_cone_is_not_seen(self) -> None:
        sim = room(Pose2(4.0, 3.0, 0.0))
        before = ping(sim, 3)
        post_at(sim, 3, 1.5, 25.0)
        assert ping(sim, 3) == pytest.approx(before)

    def test_a_ping_costs_well_under_a_millisecond_of_cpu(self) -> None:
        # CPU time of this thread, not wall time: a busy machine does not fail it. About
        # 27 us measured; the bound leaves a slow machine 30 times that.
        sim = room(Pose2(4.0, 3.0, 0.3))
        ring = SonarRing(sim.space, EmulatorConfig(), np.random.default_rng(0))
        pose = sim.body.pose_w
        start = time.thread_time()
        for k in range(800):
            ring.range_m(k % 16, pose)
        per_ping_s = (time.thread_time() - start) / 800
        assert per_ping_s < 1e-3, f"{per_ping_s * 1e6:.0f} us a ping"


class TestSpecularMisses:
    def test_a_grazing_wall_is_missed_and_a_facing_wall_echoes(self) -> None:
        # 0.9 m from the y = 0 wall, turned 28 degrees to the left: sonar 6 (-50 deg)
        # meets the wall 68 deg from its normal, sonar 7 (-90 deg) 28 deg from it.
        sim = room(Pose2(6.0, 0.9, math.radians(28.0)))
        _, y, axis = transducer_w(sim, 6)
        along_axis_m = (y - WALL_HALF_THICKNESS_M) / -math.sin(axis)
        assert along_axis_m < 4.0
        assert ping(sim, 6, ONE_RAY) == 5.0  # glanced away: no echo
        assert ping(sim, 6) == 5.0  # so did every ray of its cone (53 to 83 deg)
        no_specular = EmulatorConfig(sonar_noise_m=0.0, sonar_rays=1,
                                     sonar_critical_angle_deg=90.0)
        assert ping(sim, 6, no_specular) == pytest.approx(along_axis_m, abs=0.005)
        _, y, axis = transducer_w(sim, 7)
        assert ping(sim, 7, ONE_RAY) == pytest.approx((y - WALL_HALF_THICKNESS_M)
                                                      / -math.sin(axis), abs=0.005)

    def test_a_person_echoes_at_grazing_geometry_where_a_board_would_not(self) -> None:
        config = SimConfig(people=PeopleConfig(count=1))
        sim = Simulation(box_room((12.0, 6.0)), config)
        sim.place_robot(Pose2(4.0, 3.0, 0.0))
        x, y, axis = transducer_w(sim, 3)
        radius = config.people.radius_m
        # The axis passes 0.9 radius from the centre: it meets the body 64 deg off normal.
        centre = (x + 2.0 * math.cos(axis) - 0.9 * radius * math.sin(axis),
                  y + 2.0 * math.sin(axis) + 0.9 * radius * math.cos(axis))
        sim.people.place(0, centre, centre)
        expected = 2.0 - radius * math.cos(math.asin(0.9))
        assert ping(sim, 3, ONE_RAY) == pytest.approx(expected, abs=0.005)
        sim.people.place(0, (1.0, 1.0), (1.0, 1.0))  # out of the way
        # A board's face met by the axis at 64 deg from its normal gives no echo.
        board = sim.add_object(PlacedObject(
            "board", (x + 2.0 * math.cos(axis), y + 2.0 * math.sin(axis)), (0.6, 0.02), 1.0,
            yaw_deg=math.degrees(axis) + 26.0))
        assert ping(sim, 3, ONE_RAY) == 5.0
        sim.remove_object(board)
        sim.add_object(PlacedObject(  # turned to face the transducer, it echoes
            "board", (x + 2.0 * math.cos(axis), y + 2.0 * math.sin(axis)), (0.6, 0.02), 1.0,
            yaw_deg=math.degrees(axis) + 90.0))
        assert ping(sim, 3, ONE_RAY) == pytest.approx(2.0 - 0.01, abs=0.005)


class TestMinimumRange:
    def test_a_wall_inside_the_minimum_range_gives_no_echo(self) -> None:
        nose_m = SimConfig().body.length_m / 2
        gap_m = 0.10 - (nose_m - SONAR_POSES[3][0])  # sonar 3 10 cm from the wall
        sim = room(Pose2(12.0 - WALL_HALF_THICKNESS_M - nose_m - gap_m, 3.0, 0.0))
        assert ping(sim, 3) == 5.0  # blind (rule 4): the bumper has to catch this
        assert ping(sim, 3, EmulatorConfig(sonar_noise_m=0.0, sonar_min_range_m=0.0)
                    ) == pytest.approx(0.10, abs=0.005)

    def test_a_wall_just_beyond_it_echoes(self) -> None:
        nose_m = SimConfig().body.length_m / 2
        sim = room(Pose2(12.0 - WALL_HALF_THICKNESS_M - (SONAR_POSES[3][0] + 0.20), 3.0, 0.0))
        assert nose_m < SONAR_POSES[3][0] + 0.20
        assert ping(sim, 3) == pytest.approx(0.20, abs=0.005)


class TestSilentObstacles:
    PANEL = PlacedObject("board", (9.0, 3.0), (3.0, 0.02), 2.0, yaw_deg=90.0, sonar=False)

    def test_a_silent_panel_is_not_heard_but_the_bumper_stops_the_robot(self) -> None:
        rig = Rig(world=replace(box_room((12.0, 6.0)), objects=(self.PANEL,)), config=QUIET)
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        heard = []
        for _ in range(150):  # 15 s at most; 2.7 m to go at 0.3 m/s
            sip = rig.run_until_sip()
            heard += [r.range_m for r in sip.sonar if r.number in (3, 4)]
            if sip.front_bumpers:
                break
        nose_x = rig.sim.body.pose_w[0] + rig.sim.config.body.length_m / 2
        assert sip.front_bumpers != 0 and len(heard) > 20
        assert nose_x == pytest.approx(9.0 - 0.01, abs=0.02)
        # Sonars 3 and 4 heard the wall behind the panel, >= 3.03 m away, or nothing up
        # close; the panel would have read 0.15 to 2.7 m.
        assert min(heard) > 2.9

    def test_the_same_panel_heard_is_echoed(self) -> None:
        sim = room(Pose2(6.0, 3.0, 0.0))
        silent = sim.add_object(self.PANEL)
        assert ping(sim, 3) > 3.0
        sim.remove_object(silent)
        sim.add_object(PlacedObject("board", (9.0, 3.0), (3.0, 0.02), 2.0, yaw_deg=90.0))
        x, _, _ = transducer_w(sim, 3)
        assert ping(sim, 3) == pytest.approx(9.0 - 0.01 - x, abs=0.01)
