"""The simulated Pioneer 3-AT: a unicycle on a pymunk box, with bumpers, stall and wheel odometry.

Rules of the model (one physics step of ``dt``):

1. **Command.** ``command(v, omega)`` stores a unicycle command clamped to the
   speed limits. It holds until the next command (like the Pioneer's VEL/RVEL).
2. **Ramp.** The wheel set-points move towards the command at most by
   ``accel_m_s2 * dt`` when speeding up, ``decel_m_s2 * dt`` when slowing down
   (a reversal first brakes to zero), and ``rot_accel_rad_s2 * dt`` in rotation.
3. **Velocity control.** In pymunk's velocity integration the body's velocity
   is *set* to the set-points along its heading: no lateral slide (skid-steer
   wheels grip sideways). The contact solver then corrects it (walls and
   furniture block it, people push it), and the corrected velocity moves the
   body at the start of the next step: a set-point acts after one physics step,
   like a motor controller's cycle. Setting the velocity before ``space.step``
   instead would move the body before the solver sees the contact, and the
   robot would sink into walls by speed * dt every step.
4. **Truth.** ``pose_w`` and ``velocity_base`` come from the body's actual
   motion over the step.
5. **Bumpers.** ``bumped_front`` / ``bumped_rear``: a contact point lies ahead
   of / behind the robot's centre during the last step.
6. **Stall.** Under a non-zero command, when the solved velocity has not
   followed the set-points (off by more than half, or 5 cm/s / 0.1 rad/s) for
   ``stall_time_s``, ``stalled`` is raised, as the P3-AT's motor stall flags.
7. **Odometry.** The wheels measure the actual motion along the heading and
   the actual turn (a stalled wheel does not turn, so odometry follows a blocked
   robot; a sideways push is not measured), times per-run scale errors
   ``1 + N(0, trans_scale_sigma)`` and ``1 + N(0, rot_scale_sigma)``, plus white
   noise of ``trans_noise_m_s`` / ``rot_noise_rad_s`` per step while the wheels
   turn (a parked robot's encoders do not tick). The measured motion is
   integrated with the same step rule as the physics (move along the heading
   at the start of the step, then turn), so with all errors at 0 odometry equals
   the true motion exactly.

Odometry frame: the robot's pose when the body was created (or last placed)
is the odometry origin, (0, 0, 0), as a Pioneer's dead reckoning at power-on.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from shared.pose import Pose2
from sim._shapes import Category, tag
from sim.config import BodyConfig, OdometryConfig

_FOLLOW_REL = 0.5  # the motion follows when within half the set-point...
_FOLLOW_ABS_M_S = 0.05  # ...or within 5 cm/s
_FOLLOW_ABS_RAD_S = 0.1  # ...or within 0.1 rad/s
_TICK_M_S = 1e-3  # slower than this the encoders do not tick (no noise)
_TICK_RAD_S = 1e-3
_CONTACT_DEPTH_M = 0.005  # contact points farther apart than this are not touching
_NOISE_BLOCK = 1024  # standard normal draws fetched at a time
_FRICTION = 0.5


def _wrap(angle_rad: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (angle_rad + math.pi) % (2 * math.pi) - math.pi


def ramp(current: float, target: float, up: float, down: float) -> float:
    """Move ``current`` towards ``target`` by at most ``up`` away from 0, ``down`` towards 0."""
    # Signs are compared, not products: the product of two tiny speeds underflows to zero.
    slowing = (current > 0 and target < current) or (current < 0 and target > current)
    if slowing:  # (or reversing)
        step = max(target - current, -down) if current > 0 else min(target - current, down)
        nxt = current + step
        crossed = nxt < 0 < current or current < 0 < nxt
        return 0.0 if crossed else nxt  # a reversal stops at zero for this step
    return current + max(-up, min(up, target - current))


class PioneerBody:
    """The robot's body in a pymunk space; see the module docstring for the model.

    Args:
        space: the simulation's space (the body and its box shape are added).
        config: size, mass and limits.
        odometry: the odometry's error model.
        start: the initial pose.
        rng: source of the odometry errors (scale errors drawn here, noise per step).
    """

    def __init__(
        self,
        space: pymunk.Space,
        config: BodyConfig,
        odometry: OdometryConfig,
        start: Pose2,
        rng: np.random.Generator,
    ) -> None:
        self.config = config
        self.odometry_config = odometry
        size = (config.length_m, config.width_m)
        self._body = pymunk.Body(config.mass_kg, pymunk.moment_for_box(config.mass_kg, size))
        self._shape = pymunk.Poly.create_box(self._body, size)
        self._shape.friction = _FRICTION
        self._body.velocity_func = self._apply_setpoints
        tag(self._shape, Category.ROBOT, 0.0)  # never an occluder; height unused
        space.add(self._body, self._shape)
        self._space = space
        self._rng = rng
        self._trans_scale = 1.0 + float(rng.normal(0.0, odometry.trans_scale_sigma))
        self._rot_scale = 1.0 + float(rng.normal(0.0, odometry.rot_scale_sigma))
        self._noise = np.empty((0, 2))
        self._noise_index = 0
        self.place(start)

    # -- state ------------------------------------------------------------------------

    @property
    def shape(self) -> pymunk.Poly:
        """The robot's box shape."""
        return self._shape

    @property
    def pose_w(self) -> Pose2:
        """True pose, world frame, yaw in [-pi, pi)."""
        x, y = self._body.position
        return Pose2(float(x), float(y), _wrap(self._body.angle))

    @property
    def velocity_base(self) -> tuple[float, float, float]:
        """True velocity (vx_m_s forward, vy_m_s left, omega_rad_s), robot frame."""
        return self._velocity_base

    @property
    def setpoint(self) -> tuple[float, float]:
        """The ramped wheel set-points (v_m_s, omega_rad_s)."""
        return self._v_set, self._w_set

    @property
    def commanded(self) -> tuple[float, float]:
        """The last command after clamping (v_m_s, omega_rad_s)."""
        return self._v_cmd, self._w_cmd

    @property
    def odom_pose(self) -> Pose2:
        """Odometry pose, odometry frame (see the module docstring)."""
        return Pose2(self._odom_x, self._odom_y, _wrap(self._odom_yaw))

    @property
    def odom_velocity(self) -> tuple[float, float]:
        """Velocity measured by the wheels over the last step (v_m_s, omega_rad_s)."""
        return self._odom_v, self._odom_w

    @property
    def odom_distance_m(self) -> float:
        """Total path length measured by odometry since the last placement, m."""
        return self._odom_distance

    @property
    def bumped_front(self) -> bool:
        """A contact ahead of the robot's centre during the last step."""
        return self._bumped_front

    @property
    def bumped_rear(self) -> bool:
        """A contact behind the robot's centre during the last step."""
        return self._bumped_rear

    @property
    def stalled(self) -> bool:
        """The motion has not followed a non-zero command for ``stall_time_s``."""
        return self._blocked_s >= self.config.stall_time_s

    # -- control ----------------------------------------------------------------------

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Set the unicycle command, clamped to the speed limits.

        Raises:
            ValueError: a value is not finite.
        """
        if not (math.isfinite(v_m_s) and math.isfinite(omega_rad_s)):
            raise ValueError(
                f"body command: values must be finite, got v={v_m_s}, omega={omega_rad_s}"
            )
        v_max, w_max = self.config.max_speed_m_s, self.config.max_omega_rad_s
        self._v_cmd = max(-v_max, min(v_max, float(v_m_s)))
        self._w_cmd = max(-w_max, min(w_max, float(omega_rad_s)))

    def place(self, pose: Pose2) -> None:
        """Put the robot at rest at ``pose``; clear bumpers and stall; restart odometry at 0."""
        self._body.position = (pose.x_m, pose.y_m)
        self._body.angle = pose.yaw_rad
        self._body.velocity = (0.0, 0.0)
        self._body.angular_velocity = 0.0
        if self._body.space is not None:
            self._space.reindex_shapes_for_body(self._body)
        self._v_cmd = self._w_cmd = self._v_set = self._w_set = 0.0
        self._velocity_base = (0.0, 0.0, 0.0)
        self._bumped_front = self._bumped_rear = False
        self._blocked_s = 0.0
        self._odom_x = self._odom_y = self._odom_yaw = 0.0
        self._odom_v = self._odom_w = 0.0
        self._odom_distance = 0.0
        self._before = (pose.x_m, pose.y_m, self._body.angle)

    # -- the step (called by the simulation around space.step) ------------------------

    def before_step(self, dt_s: float) -> None:
        """Ramp the set-points (rule 2); remember the pose the step starts from."""
        c = self.config
        self._v_set = ramp(self._v_set, self._v_cmd, c.accel_m_s2 * dt_s, c.decel_m_s2 * dt_s)
        self._w_set = ramp(
            self._w_set, self._w_cmd, c.rot_accel_rad_s2 * dt_s, c.rot_accel_rad_s2 * dt_s
        )
        x, y = self._body.position
        self._before = (x, y, self._body.angle)

    def _apply_setpoints(
        self, body: pymunk.Body, gravity: object, damping: float, dt: float
    ) -> None:
        """pymunk's velocity integration for the robot (rule 3)."""
        heading = body.rotation_vector
        body.velocity = (self._v_set * heading.x, self._v_set * heading.y)
        body.angular_velocity = self._w_set

    def after_step(self, dt_s: float) -> None:
        """Read the actual motion; update truth, bumpers, stall and odometry (rules 4-7)."""
        x0, y0, a0 = self._before
        x, y = self._body.position
        dx, dy, dyaw = x - x0, y - y0, self._body.angle - a0
        c0, s0 = math.cos(a0), math.sin(a0)
        forward = c0 * dx + s0 * dy
        self._velocity_base = (forward / dt_s, (c0 * dy - s0 * dx) / dt_s, dyaw / dt_s)
        self._update_bumpers()
        self._update_stall(dt_s)
        self._integrate_odometry(forward, dyaw, dt_s)

    def _update_bumpers(self) -> None:
        self._bumped_front = self._bumped_rear = False
        self._body.each_arbiter(self._read_contacts)

    def _read_contacts(self, arbiter: pymunk.Arbiter) -> None:
        for point in arbiter.contact_point_set.points:
            if point.distance > _CONTACT_DEPTH_M:
                continue
            local = self._body.world_to_local(point.point_a)
            if local.x > 0:
                self._bumped_front = True
            elif local.x < 0:
                self._bumped_rear = True

    def _update_stall(self, dt_s: float) -> None:
        if self._v_cmd == 0 and self._w_cmd == 0:
            self._blocked_s = 0.0
            return
        velocity = self._body.velocity.dot(self._body.rotation_vector)  # solved, along the heading
        omega = self._body.angular_velocity
        follows = abs(velocity - self._v_set) <= max(
            _FOLLOW_ABS_M_S, _FOLLOW_REL * abs(self._v_set)
        ) and abs(omega - self._w_set) <= max(_FOLLOW_ABS_RAD_S, _FOLLOW_REL * abs(self._w_set))
        self._blocked_s = 0.0 if follows else self._blocked_s + dt_s

    def _integrate_odometry(self, forward_m: float, dyaw_rad: float, dt_s: float) -> None:
        ds = forward_m * self._trans_scale
        dth = dyaw_rad * self._rot_scale
        if abs(forward_m) > _TICK_M_S * dt_s or abs(dyaw_rad) > _TICK_RAD_S * dt_s:
            n_trans, n_rot = self._next_noise()
            ds += n_trans * self.odometry_config.trans_noise_m_s * dt_s
            dth += n_rot * self.odometry_config.rot_noise_rad_s * dt_s
        self._odom_x += ds * math.cos(self._odom_yaw)
        self._odom_y += ds * math.sin(self._odom_yaw)
        self._odom_yaw += dth
        self._odom_distance += abs(ds)
        self._odom_v, self._odom_w = ds / dt_s, dth / dt_s

    def _next_noise(self) -> tuple[float, float]:
        if self._noise_index >= len(self._noise):
            self._noise = self._rng.standard_normal((_NOISE_BLOCK, 2))
            self._noise_index = 0
        n = self._noise[self._noise_index]
        self._noise_index += 1
        return float(n[0]), float(n[1])
