"""The firmware motion controller on its own: targets, limits, profile (no physics)."""

from __future__ import annotations

import math

import pytest

from shared.aria import ConfigPacket
from sim.pioneer.motion import MotionController

DT_S = 0.01
FLASH = ConfigPacket()


def run(m: MotionController, seconds: float, pose=(0.0, 0.0, 0.0)) -> list[tuple[float, float]]:
    return [m.step(DT_S, pose) for _ in range(round(seconds / DT_S))]


@pytest.fixture
def m() -> MotionController:
    controller = MotionController(FLASH)
    assert controller.enable(True)
    return controller


class TestProfile:
    def test_accelerates_at_seta_and_brakes_at_the_decel(self, m: MotionController) -> None:
        m.set_accel(0.5)
        m.set_accel(-1.0)
        m.set_velocity(0.5)
        v = [cmd[0] for cmd in run(m, 0.5)]
        assert v[0] == pytest.approx(0.5 * DT_S)
        assert v[-1] == pytest.approx(min(0.25, FLASH.trans_vel_max_m_s))
        m.set_velocity(0.0)
        v = [cmd[0] for cmd in run(m, 0.1)]
        assert v[0] == pytest.approx(0.25 - 1.0 * DT_S)

    def test_limits_clamp_to_the_tops(self, m: MotionController) -> None:
        m.set_max_velocity(100.0)
        m.set_max_rot_velocity(100.0)
        assert m.limits.trans_vel_max_m_s == FLASH.trans_vel_top_m_s
        assert m.limits.rot_vel_max_rad_s == FLASH.rot_vel_top_rad_s
        m.set_velocity(-5.0)
        assert run(m, 10.0)[-1][0] == pytest.approx(-FLASH.trans_vel_top_m_s)

    def test_setra_signs(self, m: MotionController) -> None:
        m.set_rot_accel(math.radians(50))
        m.set_rot_accel(-math.radians(200))
        assert m.limits.rot_accel_rad_s2 == pytest.approx(math.radians(50))
        assert m.limits.rot_decel_rad_s2 == pytest.approx(math.radians(200))

    def test_motion_ignored_while_motors_off(self) -> None:
        m = MotionController(FLASH)
        m.set_velocity(0.3)
        m.enable(True)
        assert run(m, 1.0)[-1] == (0.0, 0.0)

    def test_e_stop_zeroes_at_once(self, m: MotionController) -> None:
        m.set_velocity(0.3)
        run(m, 2.0)
        m.e_stop()
        assert m.step(DT_S, (0.0, 0.0, 0.0)) == (0.0, 0.0) and not m.motors_enabled

    def test_halt_keeps_the_targets_and_resume_drives_on(self, m: MotionController) -> None:
        m.set_velocity(0.3)
        run(m, 2.0)
        m.halt()
        assert run(m, 2.0)[-1][0] == 0.0
        m.resume()
        assert run(m, 2.0)[-1][0] == pytest.approx(0.3)

    def test_button_refuses_enable(self, m: MotionController) -> None:
        m.press_stop_button(True)
        assert not m.enable(True) and not m.motors_enabled
        m.press_stop_button(False)
        assert not m.motors_enabled and m.enable(True)


class TestPositionTargets:
    def test_heading_takes_the_short_way_across_pi(self, m: MotionController) -> None:
        m.set_heading(math.radians(179))
        omega = run(m, 0.5, pose=(0.0, 0.0, math.radians(-179)))[-1][1]
        assert omega < 0  # -179 -> 179 deg is 2 deg clockwise

    def test_dchead_moves_the_setpoint(self, m: MotionController) -> None:
        m.set_heading(0.5)
        m.turn_setpoint_by(0.25, (0.0, 0.0, 0.0))
        assert m.heading_target_rad == pytest.approx(0.75)
        m.turn_by(0.1, (0.0, 0.0, 0.2))
        assert m.heading_target_rad == pytest.approx(0.3)

    def test_move_slows_to_its_goal(self, m: MotionController) -> None:
        pose = [0.0, 0.0, math.pi]  # facing -x: a MOVE goes along the heading
        m.move(-0.4, tuple(pose))
        for _ in range(1000):
            v, _ = m.step(DT_S, tuple(pose))
            pose[0] += v * DT_S * math.cos(pose[2])
        assert pose[0] == pytest.approx(0.4, abs=0.01)
        assert m.step(DT_S, tuple(pose))[0] == pytest.approx(0.0, abs=1e-3)
