"""``DemoLog``: the robot's field log of ``vmnav demo``, plus the simulator's ground truth.

A :class:`robot.field_log.FieldLog` (the robot's runtime records its missions, events
and notes into it, as on a real robot) that also takes the simulator's truth from
:meth:`DemoLog.add`, an ``on_cycle`` consumer of :func:`tools.harness.demo.repeat_in_sim`:

* :data:`TRUTH_TF`: the true pose ``world`` -> ``base_link_truth`` and ``world`` -> ``odom``
  (the odometry frame placed by the first cycle's truth), so the 3D panel shows the
  odometry's drift. Never on a real robot.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING

from robot.field_log import FieldLog
from shared.config import CameraMountConfig, LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.pose import Pose2

if TYPE_CHECKING:
    from sim.renderer import RenderedFrame
    from sim.simulation import Simulation
    from tools.harness.demo import CycleSample

TRUTH_TF = "/sim/truth/tf"
"""foxglove.FrameTransforms from the simulator's ground truth (never on a real robot)."""
FRAME_WORLD = "world"
FRAME_BASE_TRUTH = "base_link_truth"
#: File name prefix of the demo's robot log.
NAME = "robot"


class DemoLog(FieldLog):
    """The demo's robot log ``<config.output_dir>/robot-NNNN.mcap``: a field log plus the truth.

    Args:
        config: the folder (``OUT/logs``), frame rate, ``replay_frames``, flushing.
        mount: the simulated camera's mount (the ``base_link`` -> ``camera`` transform).
        run: key-value metadata ``"run"`` (goal, routes, seed, ...).
        unix_offset_ns: Unix time at the simulation clock's zero, ns: the wall time the
            run started (so the log shows the run's date and stays deterministic given it).
    """

    def __init__(self, config: LogConfig, mount: CameraMountConfig,
                 run: Mapping[str, str], *, unix_offset_ns: int) -> None:
        super().__init__(config, NAME, mount, run, unix_offset_ns=unix_offset_ns)
        self._world_odom: Pose2 | None = None

    def add(self, sim: Simulation, frame: RenderedFrame, sample: CycleSample) -> None:
        """Log the truth of one mission cycle (the ``on_cycle`` of
        :func:`tools.harness.demo.repeat_in_sim`); the cycle itself comes from the runtime."""
        odom = sample.record.base.odom_pose
        if self._world_odom is None:
            self._world_odom = world_odom(sample.pose_w, odom)
        self._writer.log_transform(sample.record.t_ns, [
            FrameTransform.planar(FRAME_WORLD, topics.FRAME_ODOM, *self._world_odom),
            FrameTransform.planar(FRAME_WORLD, FRAME_BASE_TRUTH, *sample.pose_w)], TRUTH_TF)


def world_odom(pose_w: Pose2, odom: Pose2) -> Pose2:
    """The odometry frame's pose in the world: T_world_base T_odom_base^-1.

    Args:
        pose_w: the true pose of the robot in the world.
        odom: its odometry pose at the same time, in ``odom``.
    """
    yaw = pose_w[2] - odom[2]
    c, s = math.cos(yaw), math.sin(yaw)
    return Pose2(pose_w[0] - (c * odom[0] - s * odom[1]), pose_w[1] - (s * odom[0] + c * odom[1]),
                 yaw)
