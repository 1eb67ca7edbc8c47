"""The simulated teach drive: the robot driven along a route in lock-step, one frame per period.

Rules of the loop (:func:`record_drive`):

1. The first frame shows the robot where it stands, before it moves.
2. Each later frame: the driver reads the true pose (a person sees where the
   robot is), the body takes the command, the simulation steps through one
   camera frame period (``SimConfig.frame_period_ns``), and the renderer draws
   the frame. Its odometry pose is the body's wheel odometry, never the truth.
3. After the driver reports the end, frames continue until the wheels' set-points
   are zero (the robot has come to rest), then the recording stops.
4. A drive that has not ended after ``max_duration_ns`` stops there; the
   caller sees it from :attr:`TeachDriver.done <sim.teach_driver.TeachDriver.done>`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.pose import Pose2
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.teach_driver import TeachDriver


@dataclass(frozen=True, eq=False)
class DriveFrame:
    """One frame of a teach drive.

    Attributes:
        t_ns: simulation time of the exposure, ns.
        image: (H, W) uint8 grey frame.
        odom_pose: wheel odometry in the drive's odometry frame.
        pose_w: true robot pose in the world, for evaluation only.
    """

    t_ns: int
    image: npt.NDArray[np.uint8]
    odom_pose: Pose2
    pose_w: Pose2


def record_drive(
    sim: Simulation, renderer: FisheyeRenderer, driver: TeachDriver, max_duration_ns: int
) -> Iterator[DriveFrame]:
    """Drive and film, one frame per camera period (see the module rules).

    Args:
        sim: the simulation, with the robot placed at the route's start.
        renderer: draws the robot's camera view.
        driver: steers along the route.
        max_duration_ns: simulated time after which the drive stops even if
            unfinished, ns.

    Yields:
        The frames in time order.
    """
    deadline_ns = sim.now_ns + max_duration_ns
    yield _frame(sim, renderer)
    while sim.now_ns < deadline_ns:
        command = driver.command(sim.body.pose_w)
        sim.body.command(command.v_m_s, command.omega_rad_s)
        sim.step_until(sim.now_ns + sim.config.frame_period_ns)
        yield _frame(sim, renderer)
        if driver.done and sim.body.setpoint == (0.0, 0.0):
            return


def _frame(sim: Simulation, renderer: FisheyeRenderer) -> DriveFrame:
    rendered = renderer.render(sim)
    return DriveFrame(
        t_ns=rendered.t_ns,
        image=rendered.image,
        odom_pose=sim.body.odom_pose,
        pose_w=rendered.pose_w,
    )
