"""The scripted teach driver (sim/teach_driver.py) and the teach recording loop."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.camera_model import CameraModel
from sim._geometry import point_segment_distances
from sim.config import SimConfig, TeachDriverConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.teach_driver import TeachDriver, resample_polyline, smooth_noise
from sim.teach_recording import record_drive
from sim.world import Route, World, load_world

FRAME_NS = SimConfig().frame_period_ns


@pytest.fixture(scope="module")
def lab() -> World:
    return load_world("lab")


def drive(world: World, route: Route, seed: int, config: TeachDriverConfig | None = None):
    """Drive ``route`` in the simulator (physics only); (true poses, speeds) once per frame."""
    sim = Simulation(world, SimConfig())
    sim.place_robot(route.start_pose())
    rng = np.random.default_rng(seed)
    driver = TeachDriver(route.waypoints, config or TeachDriverConfig(), rng)
    poses, speeds = [], []
    while not driver.done and sim.now_ns < 200e9:
        command = driver.command(sim.body.pose_w)
        sim.body.command(command.v_m_s, command.omega_rad_s)
        sim.step_until(sim.now_ns + FRAME_NS)
        poses.append(sim.body.pose_w)
        speeds.append(sim.body.velocity_base[0])
    return driver, np.array(poses), np.array(speeds)


def route_named(world: World, name: str) -> Route:
    return next(r for r in world.routes if r.name == name)


class TestHelpers:
    def test_resample_keeps_the_vertices_and_the_spacing(self) -> None:
        waypoints = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.33]])
        points, s = resample_polyline(waypoints, 0.1)
        assert points[0].tolist() == [0.0, 0.0] and points[-1].tolist() == [1.0, 0.33]
        assert any(np.allclose(p, [1.0, 0.0]) for p in points)
        assert np.diff(s).max() <= 0.1 + 1e-12
        assert s[-1] == pytest.approx(1.33)

    @settings(max_examples=30, deadline=None)
    @given(seed=st.integers(0, 2**32 - 1), peak=st.floats(0.001, 1.0))
    def test_smooth_noise_peaks_at_the_amplitude(self, seed: int, peak: float) -> None:
        s = np.linspace(0.0, 20.0, 401)
        values = smooth_noise(s, peak, (2.0, 6.0), np.random.default_rng(seed))
        assert np.abs(values).max() == pytest.approx(peak)
        # Smooth: wavelengths >= 2 m bound the slope by 2 pi * 3 * peak / 2 m, roughly.
        assert np.abs(np.diff(values) / np.diff(s)).max() <= 3 * math.pi * peak * 1.01

    def test_zero_amplitude_is_no_noise(self) -> None:
        s = np.linspace(0.0, 5.0, 11)
        assert not smooth_noise(s, 0.0, (2.0, 6.0), np.random.default_rng(0)).any()


class TestTeachDriver:
    def test_the_wander_is_bounded_and_fades_out_at_the_ends(self, lab: World) -> None:
        config = TeachDriverConfig(wander_amplitude_m=0.05)
        waypoints = route_named(lab, "corridor").waypoints
        driver = TeachDriver(waypoints, config, np.random.default_rng(3))
        assert np.abs(driver.wander_m).max() <= 0.05 + 1e-12
        assert np.abs(driver.wander_m).max() > 0.03
        assert driver.wander_m[0] == 0.0 and driver.wander_m[-1] == pytest.approx(0.0, abs=1e-12)

    def test_same_seed_same_drive_other_seed_other_drive(self, lab: World) -> None:
        route = route_named(lab, "corridor")
        _, a, _ = drive(lab, route, seed=7)
        _, b, _ = drive(lab, route, seed=7)
        _, c, _ = drive(lab, route, seed=8)
        assert np.array_equal(a, b)
        n = min(len(a), len(c))
        assert np.abs(a[:n, 1] - c[:n, 1]).max() > 0.01

    def test_drives_the_corridor_wavy_within_a_few_centimetres(self, lab: World) -> None:
        route = route_named(lab, "corridor")
        driver, poses, speeds = drive(lab, route, seed=1)
        assert driver.done
        waypoints = np.array(route.waypoints)
        lateral = poses[:, 1] - waypoints[0, 1]  # the corridor route runs along y = 10
        assert np.abs(lateral).max() <= 0.045  # amplitude 4 cm plus pursuit overshoot
        assert lateral.std() >= 0.005  # not exact: it wanders
        assert np.hypot(*(poses[-1, :2] - waypoints[-1])) <= 0.15
        # Cruising: past the start-up and before the slow-down (1 m clear of each end).
        (x_start, _), (x_end, _) = waypoints
        cruise = speeds[(poses[:, 0] > x_start + 1.0) & (poses[:, 0] < x_end - 1.0)]
        assert cruise.min() >= 0.3 * 0.88 and cruise.max() <= 0.3 * 1.12
        assert cruise.max() - cruise.min() >= 0.02  # the speed drifts

    def test_follows_a_route_with_turns(self, lab: World) -> None:
        route = route_named(lab, "office_loop")
        driver, poses, _ = drive(lab, route, seed=1)
        assert driver.done
        waypoints = np.array(route.waypoints)
        off = point_segment_distances(poses[:, :2], waypoints[:-1], waypoints[1:]).min(axis=1)
        assert off.max() <= 0.2  # cutting corners a little, like a person

    def test_bad_waypoints(self) -> None:
        with pytest.raises(ValueError, match="waypoints_xy must be"):
            TeachDriver([[0.0, 0.0]], TeachDriverConfig(), np.random.default_rng(0))


class TestRecordDrive:
    def test_frames_every_period_with_odometry_until_the_robot_stops(self, lab: World) -> None:
        world = dataclasses.replace(lab, routes=(Route("short", ((2.0, 10.0), (3.0, 10.0))),))
        sim = Simulation(world, SimConfig())
        route = world.routes[0]
        sim.place_robot(route.start_pose())
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        driver = TeachDriver(route.waypoints, TeachDriverConfig(), np.random.default_rng(0))
        frames = list(record_drive(sim, renderer, driver, 60_000_000_000))
        assert driver.done and sim.body.setpoint == (0.0, 0.0)
        times = np.array([f.t_ns for f in frames])
        assert times[0] == 0 and (np.diff(times) >= FRAME_NS).all()
        assert frames[0].odom_pose == (0.0, 0.0, 0.0)
        assert frames[0].pose_w == pytest.approx((2.0, 10.0, 0.0))
        # Odometry is measured from the start (its own frame), with its own errors.
        x_odom = frames[-1].odom_pose[0]
        x_true = frames[-1].pose_w[0] - 2.0
        assert x_odom == pytest.approx(x_true, abs=0.05) and x_odom != x_true
        assert frames[-1].image.shape == (600, 800)

    def test_stops_at_the_time_limit(self, lab: World) -> None:
        sim = Simulation(lab, SimConfig())
        route = route_named(lab, "corridor")
        sim.place_robot(route.start_pose())
        renderer = FisheyeRenderer.for_simulation(sim, CameraModel.default())
        driver = TeachDriver(route.waypoints, TeachDriverConfig(), np.random.default_rng(0))
        frames = list(record_drive(sim, renderer, driver, 5 * FRAME_NS))
        assert len(frames) == 6 and not driver.done
