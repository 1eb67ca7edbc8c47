"""The simulated Pioneer body as a :class:`shared.interfaces.MobileBase`, in lock-step.

Commands go to :meth:`sim.body.PioneerBody.command` (the body ramps and clamps
them as the real firmware does); the state reports the body's wheel odometry
(never the truth), its bumpers and stall detector. The simulated battery holds
:data:`BATTERY_V` and the motors are always enabled.
"""

from __future__ import annotations

from shared.interfaces import BaseState
from sim.simulation import Simulation

#: Voltage the simulated battery reports, V (a charged Pioneer 3-AT pack).
BATTERY_V = 13.0


class SimBase:
    """Velocity commands to, and odometry from, the simulated body.

    Args:
        sim: the simulation whose robot body is driven.
    """

    def __init__(self, sim: Simulation) -> None:
        self._body = sim.body

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Drive at ``v_m_s`` (m/s, forward) and ``omega_rad_s`` (rad/s, counter-clockwise)."""
        self._body.command(v_m_s, omega_rad_s)

    def stop(self) -> None:
        """Command zero velocity."""
        self._body.command(0.0, 0.0)

    def state(self) -> BaseState:
        """Wheel odometry, bumpers (front or rear), stall, battery and motor state."""
        body = self._body
        return BaseState(
            odom_pose=body.odom_pose,
            odom_distance_m=body.odom_distance_m,
            bumped=body.bumped_front or body.bumped_rear,
            stalled=body.stalled,
            battery_v=BATTERY_V,
            motors_enabled=True,
        )
