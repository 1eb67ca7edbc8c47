from __future__ import annotations

import math

import numpy as np
import pytest

from sim.driver import PurePursuit


def drive(
    driver: PurePursuit, pose: tuple[float, float, float], dt: float = 0.05, steps: int = 4000
):
    """Integrate ideal unicycle kinematics under the driver; returns the visited poses."""
    x, y, yaw = pose
    poses = [pose]
    for _ in range(steps):
        cmd = driver.command((x, y, yaw))
        if driver.done:
            break
        x += cmd.v_m_s * math.cos(yaw) * dt
        y += cmd.v_m_s * math.sin(yaw) * dt
        yaw += cmd.omega_rad_s * dt
        poses.append((x, y, yaw))
    return np.array(poses)


class TestPurePursuit:
    def test_reaches_the_end_of_an_l_shaped_path_and_stays_near_it(self) -> None:
        path = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
        driver = PurePursuit(path, speed_m_s=0.4, lookahead_m=0.6)
        poses = drive(driver, (0.0, 0.0, 0.0))
        assert driver.done
        assert np.hypot(*(poses[-1, :2] - path[-1])) < 0.3
        # Cross-track error stays small: distance to the nearest of the two legs.
        d_leg1 = np.where((poses[:, 0] <= 5.0), np.abs(poses[:, 1]), np.inf)
        d_leg2 = np.where((poses[:, 1] >= 0.0), np.abs(poses[:, 0] - 5.0), np.inf)
        assert np.minimum(d_leg1, d_leg2).max() < 0.35

    def test_converges_from_an_offset_start(self) -> None:
        driver = PurePursuit([[0.0, 0.0], [10.0, 0.0]], speed_m_s=0.4, lookahead_m=0.8)
        poses = drive(driver, (0.0, 0.5, math.radians(20)))
        assert abs(poses[-1, 1]) < 0.05

    def test_command_limits(self) -> None:
        driver = PurePursuit([[0.0, 0.0], [0.0, 5.0]], speed_m_s=0.4, max_omega_rad_s=0.5)
        cmd = driver.command((0.0, 0.0, math.pi))  # facing away from the path
        assert abs(cmd.omega_rad_s) <= 0.5
        assert 0 < cmd.v_m_s <= 0.4

    def test_needs_two_waypoints(self) -> None:
        with pytest.raises(ValueError, match="waypoints_xy"):
            PurePursuit([[0.0, 0.0]])


def test_a_loop_passing_its_own_end_is_driven_in_full() -> None:
    # A 4 m square loop whose end (5 cm before the origin) the robot passes right after starting.
    loop = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0], [-0.05, 0.0]])
    loop = np.vstack([[[-0.5, 0.0]], loop])
    driver = PurePursuit(loop, speed_m_s=0.3, lookahead_m=0.3, goal_tolerance_m=0.1)
    poses = drive(driver, (-0.5, 0.0, 0.0))
    assert driver.done
    travelled = np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T))
    assert travelled > 3.5
