"""``DemoLog``: the robot's field log of ``vmnav demo``'s repeat, ``OUT/logs/robot-NNNN.mcap``.

An ``on_cycle`` consumer of :func:`tools.demo.repeat_in_sim`: each servo cycle goes to
a :class:`shared.logs.writer.LogWriter` (whose thread encodes and writes, so the loop
only queues), stamped with the cycle's frame time on the simulation clock:

* :data:`~shared.logs.topics.CAMERA_IMAGE`: the grey frame as JPEG, frame ``camera``, at
  most ``LogConfig.frame_rate_hz``;
* :data:`~shared.logs.topics.CAMERA_ANNOTATIONS`: on the same timestamp as each logged
  frame, its corners and a label (target key image, matches);
* :data:`~shared.logs.topics.SERVO_STATE`: one flat ``vmnav.ServoState`` per cycle (the
  schema's fields plus the extras of :func:`servo_state`);
* :data:`~shared.logs.topics.CMD_VEL`: the servo's command, on cycles that sent one;
* :data:`~shared.logs.topics.TF`: the odometry ``odom`` -> ``base_link`` and the static
  ``base_link`` -> ``camera`` of the camera mount (repeated, so a seek finds it);
* :data:`TRUTH_TF` (simulator only): the true pose ``world`` -> ``base_link_truth`` and
  ``world`` -> ``odom`` (the odometry frame placed by the first cycle's truth), so the 3D
  panel shows the odometry's drift;
* :data:`~shared.logs.topics.LOG`: the application's events (:class:`robot.mission_run.AppEvent`),
  written after the run by :meth:`DemoLog.log_events` (the cycle record does not carry them).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial.transform import Rotation

from shared.camera_mount import rotation_base_cam
from shared.config import CameraMountConfig, LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.logs.writer import LogStats, LogWriter

if TYPE_CHECKING:
    from robot.mission_run import AppEvent, CycleRecord
    from shared.memory import VisualMemory
    from sim.renderer import RenderedFrame
    from sim.simulation import Simulation
    from tools.demo import CycleSample

TRUTH_TF = "/sim/truth/tf"
"""foxglove.FrameTransforms from the simulator's ground truth (never on a real robot)."""
FRAME_WORLD = "world"
FRAME_BASE_TRUTH = "base_link_truth"
#: Log level of the application's events by kind (others are INFO).
_EVENT_LEVELS = {"lost": "WARNING"}
_EVENT_SOURCE = "robot.mission_run"


def camera_transform(mount: CameraMountConfig) -> FrameTransform:
    """The static ``base_link`` -> ``camera`` of a camera mount.

    ``camera`` is the optical frame (x right, y down, z along the optical axis), the
    frame of the logged images; ``base_link`` is on the floor under the robot's centre.
    """
    x, y, z, w = Rotation.from_matrix(rotation_base_cam(mount)).as_quat()
    return FrameTransform(topics.FRAME_BASE, topics.FRAME_CAMERA,
                          (mount.x_m, mount.y_m, mount.height_m), (w, x, y, z))


def servo_state(record: CycleRecord, key_image_id: int | None) -> dict[str, Any]:
    """The flat ``vmnav.ServoState`` of one cycle.

    Besides the schema's fields: ``mission_state`` (:class:`robot.mission.MissionState`
    value), ``err_image_max_px`` / ``err_points_px`` (the paper's errImageMax and
    errPoints; null when not computed or without inliers), and the vision's raw estimate
    ``lateral_error_raw_m``, ``angular_error_raw_rad``, ``progress_raw_m`` (null unless
    usable) next to the filtered ones the law used. Outside FOLLOWING, ``target_index``
    is -1 and the command is 0 (the application stops the base), and
    ``matched_points`` are those of the localization.

    Args:
        record: the cycle.
        key_image_id: the key image headed for (None when not following).
    """
    follow, vision = record.follow, None if record.follow is None else record.follow.vision
    ok = vision is not None and vision.state.ok
    matches = (vision.matches if vision is not None
               else record.localization.matches if record.localization is not None else 0)
    return {
        "stamp_ns": record.t_ns,
        "mode": "repeat",
        "mission_state": record.state.value,
        "target_index": -1 if follow is None else follow.target_index,
        "key_image_id": key_image_id,
        "lateral_error_m": None if follow is None else follow.y_m,
        "angular_error_rad": None if follow is None else follow.theta_rad,
        "progress_m": None if follow is None else follow.s_m,
        "v_m_s": 0.0 if follow is None else follow.twist.v_m_s,
        "omega_rad_s": 0.0 if follow is None else follow.twist.omega_rad_s,
        "matched_points": matches,
        "inliers": vision.state.n_inliers if vision is not None else None,
        "lost": follow is not None and follow.lost is not None,
        "err_image_max_px": None if vision is None else vision.image_errors.err_image_max_px,
        "err_points_px": None if vision is None else vision.image_errors.err_points_px,
        "lateral_error_raw_m": vision.state.y_m if ok else None,
        "angular_error_raw_rad": vision.state.theta_rad if ok else None,
        "progress_raw_m": vision.state.s_m if ok else None,
    }


class DemoLog:
    """Writes the demo's robot log; pass :meth:`add` as ``on_cycle``.

    The file is opened at the first cycle, so a run that fails before it (a bad goal)
    leaves no empty log behind.

    Args:
        folder: the log folder (``OUT/logs``); files are ``robot-NNNN.mcap``, numbered
            after any already there.
        memory: the memory followed (turns target indices into key image ids).
        mount: the simulated camera's mount (the ``base_link`` -> ``camera`` transform).
        config: frame rate, JPEG quality, flushing; its ``output_dir`` is replaced by
            ``folder``.
        run: key-value metadata ``"run"`` stored in the file (goal, routes, seed, ...).
    """

    def __init__(self, folder: Path, memory: VisualMemory, mount: CameraMountConfig,
                 config: LogConfig | None = None, run: Mapping[str, str] | None = None) -> None:
        self._memory = memory
        self._camera = camera_transform(mount)
        self._config = dataclasses.replace(config or LogConfig(), output_dir=str(folder))
        self._run = run
        self._targets: dict[tuple[int, ...], tuple[int, ...]] = {}
        self._world_odom: tuple[float, float, float] | None = None
        self._writer: LogWriter | None = None

    def add(self, sim: Simulation, frame: RenderedFrame, sample: CycleSample) -> None:
        """Log one cycle (the ``on_cycle`` of :func:`tools.demo.repeat_in_sim`)."""
        writer = self._writer or self._open()
        record = sample.record
        t_ns, follow = record.t_ns, record.follow
        key_id = None if follow is None else self._key_image_id(record.route, follow.target_index)
        state = servo_state(record, key_id)
        if writer.log_image(t_ns, topics.CAMERA_IMAGE, frame.image):
            # OpenCV's pixel centres are at integers, Foxglove's at +0.5 (messages.image_points).
            corners = (np.zeros((0, 2)) if follow is None else follow.corners_xy + 0.5)
            writer.log_points(t_ns, topics.CAMERA_ANNOTATIONS, corners,
                              label=_label(record.state.value, key_id, state["matched_points"]))
        writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState", state)
        if follow is not None:
            writer.log_json(t_ns, topics.CMD_VEL, "vmnav.Command", {
                "stamp_ns": t_ns, "linear_x_m_s": follow.twist.v_m_s,
                "angular_z_rad_s": follow.twist.omega_rad_s, "source": "servo"})
        odom = record.base.odom_pose
        writer.log_transform(t_ns, [
            FrameTransform.planar(topics.FRAME_ODOM, topics.FRAME_BASE, *odom), self._camera])
        if self._world_odom is None:
            self._world_odom = _world_odom(sample.pose_w, odom)
        writer.log_transform(t_ns, [
            FrameTransform.planar(FRAME_WORLD, topics.FRAME_ODOM, *self._world_odom),
            FrameTransform.planar(FRAME_WORLD, FRAME_BASE_TRUTH, *sample.pose_w)], TRUTH_TF)

    def log_events(self, events: Sequence[AppEvent]) -> None:
        """Log the application's events as ``foxglove.Log`` lines on their own times."""
        if self._writer is None:
            return
        for event in events:
            self._writer.log_text(event.t_ns, _EVENT_LEVELS.get(event.kind, "INFO"),
                                  f"{event.kind} {event.reason}: {event.detail}", _EVENT_SOURCE)

    def close(self) -> LogStats | None:
        """Write what is queued and finish the file.

        Returns:
            The writer's final counters (files, messages written, dropped), or None
            when no cycle was logged (no file).
        """
        return None if self._writer is None else self._writer.close()

    def _open(self) -> LogWriter:
        self._writer = LogWriter(self._config, "robot")
        if self._run is not None:
            self._writer.add_metadata("run", self._run)
        return self._writer

    def _key_image_id(self, route: tuple[int, ...], target_index: int) -> int | None:
        from robot.follower import targets_from_route

        if route not in self._targets:
            self._targets[route] = targets_from_route(self._memory, list(route))
        targets = self._targets[route]
        return targets[target_index] if 0 <= target_index < len(targets) else None


def _label(state: str, key_id: int | None, matches: int) -> str:
    return (f"{state}: {matches} matches" if key_id is None
            else f"key {key_id}: {matches} matches")


def _world_odom(pose_w: tuple[float, float, float],
                odom: tuple[float, float, float]) -> tuple[float, float, float]:
    """The odometry frame in the world, (x_m, y_m, yaw_rad): T_world_base T_odom_base^-1."""
    yaw = pose_w[2] - odom[2]
    c, s = math.cos(yaw), math.sin(yaw)
    return (pose_w[0] - (c * odom[0] - s * odom[1]), pose_w[1] - (s * odom[0] + c * odom[1]), yaw)
