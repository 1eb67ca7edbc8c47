"""The emulated Pioneer's firmware motion controller: client commands -> body commands.

Rules (ARCOS, as aria-protocol.md §4, §7 and §9 describe it):

1. **Motors** are off at power-up and at every new connection, and motion commands
   are ignored while they are off. ENABLE 1 turns them on unless the STOP button is
   pressed (p2os #69); ENABLE 0, E_STOP and pressing the button turn them off and
   clear the targets.
2. **Targets.** Translation is a velocity (VEL, VEL2) or a distance to go (MOVE);
   rotation a velocity (RVEL, ROTATE, VEL2) or a heading to reach (HEAD, DHEAD,
   DCHEAD). A command for an axis replaces that axis's target. STOP zeroes both
   with the motors left on; so do VEL 0 + RVEL 0 (ARIA's ``stop()``).
3. **Limits.** Velocities are clamped to the SETV / SETRV maxima, which are clamped
   to the tops (CONFIG TransVelTop / RotVelTop); SETA / SETRA set the acceleration
   (argument > 0) or the deceleration (< 0), up to the acceleration tops.
4. **Profile.** Every physics step the profiled velocity moves towards the target by
   at most acceleration * dt when speeding up, deceleration * dt when slowing down
   (the body's ramp rule, :func:`sim.body.ramp`). A distance or heading target asks
   for the speed that still stops in what is left: min(max, sqrt(2 decel d), k d).
5. **Watchdog.** :meth:`MotionController.halt` brings the profile to zero and keeps
   the targets; :meth:`MotionController.resume` drives on (ARCOS resumes the last
   motion when packets return).
6. **E_STOP** zeroes the profile at once; the body then brakes at its own physical
   limit (``BodyConfig.decel_m_s2``).

Distances and headings are the firmware's own, from its odometry (what the SIP
reports): poses are (x_m, y_m, th_rad) in the odometry frame.
"""

from __future__ import annotations

import math
from dataclasses import replace

from shared.aria import ConfigPacket
from shared.aria.p3at import DIFF_CONV_RAD_PER_M
from shared.pose import Pose2
from sim.body import ramp

MOVE_TOLERANCE_M = 0.005
"""A MOVE is done within this distance of its goal, m."""
HEADING_TOLERANCE_RAD = math.radians(1.0)
"""A heading target holds still within this angle of it, rad."""
APPROACH_GAIN_PER_S = 2.0
"""k of rule 4: near a goal the speed is k * (what is left), 1/s (no chatter at the goal)."""


def _wrap(angle_rad: float) -> float:
    return (angle_rad + math.pi) % (2 * math.pi) - math.pi


def _approach(left: float, v_max: float, decel: float) -> float:
    """Signed speed towards a goal ``left`` away (m or rad) that can still stop there."""
    speed = min(v_max, math.sqrt(2 * decel * abs(left)), APPROACH_GAIN_PER_S * abs(left))
    return math.copysign(speed, left)


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


class MotionController:
    """Velocity targets, limits and the profile of one robot (see the module rules).

    Args:
        flash: the robot's stored configuration (CONFIG reply); its maxima, tops and
            accelerations are the power-up values.
    """

    def __init__(self, flash: ConfigPacket) -> None:
        self._flash = flash
        self._button = False
        self.reset()

    # -- state ------------------------------------------------------------------

    @property
    def motors_enabled(self) -> bool:
        """SIP FLAGS bit 0."""
        return self._motors

    @property
    def stop_button_pressed(self) -> bool:
        """SIP FLAGS bit 5 (the red STOP button, not the E_STOP command)."""
        return self._button

    @property
    def heading_target_rad(self) -> float | None:
        """The heading being steered to (HEAD, DHEAD, DCHEAD), odometry frame; None if none."""
        return self._heading_goal

    @property
    def limits(self) -> ConfigPacket:
        """The flash with the current SETV/SETRV maxima and SETA/SETRA rates (the CONFIG reply)."""
        return self._limits

    # -- commands ---------------------------------------------------------------

    def reset(self) -> None:
        """Power-up / new connection: motors off, targets and profile zero, flash limits."""
        self._limits = self._flash
        self._motors = False
        self._halted = False
        self._v = self._w = 0.0
        self._clear_targets()

    def enable(self, on: bool) -> bool:
        """ENABLE: motors on or off; returns False when refused (STOP button pressed)."""
        if on and self._button:
            return False
        if not on:
            self._clear_targets()
        self._motors = on
        return True

    def press_stop_button(self, pressed: bool) -> None:
        """Press (motors off, targets cleared) or release (motors stay off) the STOP button."""
        self._button = pressed
        if pressed:
            self.enable(False)

    def e_stop(self) -> None:
        """E_STOP: profile zero now, motors off until the next ENABLE 1 (rules 1, 6)."""
        self.enable(False)
        self._v = self._w = 0.0

    def stop(self) -> None:
        """STOP: both targets zero; the motors stay on."""
        self._clear_targets()

    def halt(self) -> None:
        """Watchdog expired: slow to a stop, keep the targets (rule 5)."""
        self._halted = True

    def resume(self) -> None:
        """Packets returned: drive on towards the kept targets."""
        self._halted = False

    def set_velocity(self, v_m_s: float) -> None:
        """VEL: translational velocity, m/s."""
        if self._motors:
            self._v_target, self._move = v_m_s, None

    def set_rot_velocity(self, omega_rad_s: float) -> None:
        """RVEL / ROTATE: rotational velocity, rad/s, counter-clockwise positive."""
        if self._motors:
            self._w_target, self._heading_goal = omega_rad_s, None

    def set_wheels(self, left_m_s: float, right_m_s: float) -> None:
        """VEL2: wheel velocities, m/s -> v = (l + r) / 2, omega = (r - l) / 2 * DiffConv."""
        self.set_velocity((left_m_s + right_m_s) / 2)
        self.set_rot_velocity((right_m_s - left_m_s) / 2 * DIFF_CONV_RAD_PER_M)

    def move(self, distance_m: float, pose: Pose2) -> None:
        """MOVE: travel ``distance_m`` (m, negative backwards) along the current heading."""
        if self._motors:
            self._move = (pose, distance_m)

    def set_heading(self, heading_rad: float) -> None:
        """HEAD: turn to this odometry heading, rad (any value; wrapped)."""
        if self._motors:
            self._heading_goal = _wrap(heading_rad)

    def turn_by(self, delta_rad: float, pose: Pose2) -> None:
        """DHEAD: turn by ``delta_rad`` from the current heading, rad."""
        self.set_heading(pose[2] + delta_rad)

    def turn_setpoint_by(self, delta_rad: float, pose: Pose2) -> None:
        """DCHEAD: move the heading setpoint by ``delta_rad`` (from the heading if none)."""
        base = self._heading_goal if self._heading_goal is not None else pose[2]
        self.set_heading(base + delta_rad)

    def set_max_velocity(self, v_max_m_s: float) -> None:
        """SETV: translational maximum, m/s, clamped to 0..TransVelTop."""
        top = self._flash.trans_vel_top_m_s
        self._set_limit(trans_vel_max_m_s=max(0.0, min(top, v_max_m_s)))

    def set_max_rot_velocity(self, omega_max_rad_s: float) -> None:
        """SETRV: rotational maximum, rad/s, clamped to 0..RotVelTop."""
        top = self._flash.rot_vel_top_rad_s
        self._set_limit(rot_vel_max_rad_s=max(0.0, min(top, omega_max_rad_s)))

    def set_accel(self, accel_m_s2: float) -> None:
        """SETA: > 0 sets the translational acceleration, < 0 the deceleration, m/s²."""
        value = min(abs(accel_m_s2), self._flash.trans_accel_top_m_s2)
        if accel_m_s2 > 0:
            self._set_limit(trans_accel_m_s2=value)
        elif accel_m_s2 < 0:
            self._set_limit(trans_decel_m_s2=value)

    def set_rot_accel(self, accel_rad_s2: float) -> None:
        """SETRA: > 0 sets the rotational acceleration, < 0 the deceleration, rad/s²."""
        value = min(abs(accel_rad_s2), self._flash.rot_accel_top_rad_s2)
        if accel_rad_s2 > 0:
            self._set_limit(rot_accel_rad_s2=value)
        elif accel_rad_s2 < 0:
            self._set_limit(rot_decel_rad_s2=value)

    # -- the physics step -------------------------------------------------------

    def step(self, dt_s: float, pose: Pose2) -> tuple[float, float]:
        """Advance the profile by ``dt_s`` (s) from odometry ``pose``.

        Returns:
            The body command (v_m_s, omega_rad_s).
        """
        lim = self._limits
        v_des = w_des = 0.0
        if self._motors and not self._halted:
            v_des = _clamp(self._translation_target(pose), lim.trans_vel_max_m_s)
            w_des = _clamp(self._rotation_target(pose), lim.rot_vel_max_rad_s)
        self._v = ramp(self._v, v_des, lim.trans_accel_m_s2 * dt_s, lim.trans_decel_m_s2 * dt_s)
        self._w = ramp(self._w, w_des, lim.rot_accel_rad_s2 * dt_s, lim.rot_decel_rad_s2 * dt_s)
        return self._v, self._w

    def _translation_target(self, pose: Pose2) -> float:
        if self._move is None:
            return self._v_target
        (x0, y0, th0), distance = self._move
        left = distance - ((pose[0] - x0) * math.cos(th0) + (pose[1] - y0) * math.sin(th0))
        if abs(left) < MOVE_TOLERANCE_M:
            self._v_target, self._move = 0.0, None
            return 0.0
        return _approach(left, self._limits.trans_vel_max_m_s, self._limits.trans_decel_m_s2)

    def _rotation_target(self, pose: Pose2) -> float:
        if self._heading_goal is None:
            return self._w_target
        left = _wrap(self._heading_goal - pose[2])
        if abs(left) < HEADING_TOLERANCE_RAD:
            return 0.0
        return _approach(left, self._limits.rot_vel_max_rad_s, self._limits.rot_decel_rad_s2)

    def _clear_targets(self) -> None:
        self._v_target = self._w_target = 0.0
        self._move: tuple[Pose2, float] | None = None
        self._heading_goal: float | None = None

    def _set_limit(self, **changes: float) -> None:
        self._limits = replace(self._limits, **changes)
