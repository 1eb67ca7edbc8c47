"""FieldLog: the robot's field log in MCAP (issue 7, item 1), ``<output_dir>/<name>-NNNN.mcap``.

Every call queues onto a :class:`shared.logs.writer.LogWriter`, whose thread builds,
encodes and writes the messages, so the control loop only copies and queues; a log
problem (queue full, disk full) is counted, never raised. Topics
(:mod:`shared.logs.topics`, mcap-logging.md sec. 3), each stamped with the data's time
on the robot's clock (the JSON messages' ``stamp_ns``; the MCAP ``log_time`` and the
Foxglove timestamps add the clock's Unix offset, :mod:`shared.logs.writer`):

* :data:`~shared.logs.topics.MISSION_START` (:meth:`FieldLog.mission_started`): a mission
  run's goal, its random generator's state and the whole config, what
  ``vmnav replay`` rebuilds the :class:`robot.mission_run.MissionRun` from;
* per mission cycle (:meth:`FieldLog.cycle`), on the frame's time:

  - :data:`~shared.logs.topics.CAMERA_IMAGE`: the frame, JPEG at most
    ``LogConfig.frame_rate_hz``; with ``LogConfig.replay_frames`` PNG, every cycle's
    (lossless, so replay is exact);
  - :data:`~shared.logs.topics.CAMERA_ANNOTATIONS`: with each logged frame, its corners
    and a label (target key image, matches);
  - :data:`~shared.logs.topics.SERVO_STATE`: one flat ``vmnav.ServoState``
    (:func:`servo_state`);
  - :data:`~shared.logs.topics.BASE_STATE`: the base's state the cycle read;
  - :data:`~shared.logs.topics.CMD_VEL`: the servo's command, on cycles that sent one;
  - :data:`~shared.logs.topics.TF`: the odometry ``odom`` -> ``base_link`` and the static
    ``base_link`` -> ``camera`` of the camera mount (repeated, so a seek finds it);

* teaching (:meth:`FieldLog.teach_frame`): the frame (JPEG, at most ``frame_rate_hz``) and
  the odometry on :data:`~shared.logs.topics.TF`, what ``vmnav memory build`` reads;
* :data:`~shared.logs.topics.SIP` (:meth:`FieldLog.sip`): the Pioneer's SIPs;
* ``/mavlink/<in|out>/<NAME>`` and :data:`~shared.logs.topics.MAVLINK_RAW`
  (:meth:`FieldLog.mavlink`): every MAVLink packet accepted and sent; what was
  rejected is counted, as a WARNING line per period that had any
  (:meth:`FieldLog.mavlink_rejected`);
* :data:`~shared.logs.topics.LOG`: mission events (:meth:`FieldLog.event`), the
  runtime's notes (:meth:`FieldLog.note`) and how the Pioneer link ended
  (:meth:`FieldLog.pioneer_closed`) as ``foxglove.Log`` lines.

Metadata ``run`` (in every file): the caller's key-values plus ``series``, an id unique
to this log, by which :func:`shared.logs.series.log_series` keeps a rotated series
together.
"""

from __future__ import annotations

import dataclasses
import logging
import uuid
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from robot.config import VmnavConfig
from robot.mission_run import AppEvent, CycleRecord
from robot.pioneer.status import LinkCounters, PioneerStatus
from shared.aria.sip import Sip
from shared.camera_mount import rotation_base_cam
from shared.config import CameraMountConfig, LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform, base_state_fields, sip_fields
from shared.logs.series import RUN_METADATA, SERIES_KEY
from shared.logs.writer import LogStats, LogWriter
from shared.pose import Pose2

#: ``foxglove.Log`` name of mission events, of the runtime's notes and of the Pioneer's end.
EVENT_SOURCE = "robot.mission_run"
NOTE_SOURCE = "robot.runtime"
PIONEER_SOURCE = "robot.pioneer"
#: ``foxglove.Log`` name of the counts of rejected MAVLink traffic.
MAVLINK_SOURCE = "robot.vehicle"
#: Log level of mission events by kind (others are INFO).
_EVENT_LEVELS = {"lost": "WARNING"}
#: Foxglove log levels from the lowest ``logging`` level each covers, highest first.
_NOTE_LEVELS = ((logging.CRITICAL, "FATAL"), (logging.ERROR, "ERROR"),
                (logging.WARNING, "WARNING"), (logging.INFO, "INFO"))


def camera_transform(mount: CameraMountConfig) -> FrameTransform:
    """The static ``base_link`` -> ``camera`` of a camera mount.

    ``camera`` is the optical frame (x right, y down, z along the optical axis), the
    frame of the logged images; ``base_link`` is on the floor under the robot's centre.
    """
    x, y, z, w = Rotation.from_matrix(rotation_base_cam(mount)).as_quat()
    return FrameTransform(topics.FRAME_BASE, topics.FRAME_CAMERA,
                          (mount.x_m, mount.y_m, mount.height_m), (w, x, y, z))


def servo_state(record: CycleRecord) -> dict[str, Any]:
    """The flat ``vmnav.ServoState`` of one cycle: every field of
    :data:`shared.logs.schemas.SERVO_STATE`, which describes them.

    Besides the servo's own state (the filtered y, theta, s the law used, the command,
    matches): ``mission_state``, ``switch_reason`` (the key image switch this cycle
    completed, else null), ``err_image_max_px`` / ``err_points_px`` (the paper's
    errImageMax and errPoints; null when not computed or without inliers), and the
    vision's raw estimate ``lateral_error_raw_m``, ``angular_error_raw_rad``,
    ``progress_raw_m`` (null unless usable). Outside FOLLOWING, ``target_index`` is -1
    and the command is 0 (the application stops the base), and ``matched_points`` are
    those of the localization.

    Args:
        record: the cycle (``key_image_id`` is its :attr:`CycleRecord.target_key`).
    """
    follow, vision = record.follow, None if record.follow is None else record.follow.vision
    ok = vision is not None and vision.state.ok
    matches = (vision.matches if vision is not None
               else record.localization.matches if record.localization is not None else 0)
    switch = None if follow is None else follow.switch
    return {
        "stamp_ns": record.t_ns,
        "mode": "repeat",
        "mission_state": record.state.value,
        "target_index": -1 if follow is None else follow.target_index,
        "key_image_id": record.target_key,
        "lateral_error_m": None if follow is None else follow.y_m,
        "angular_error_rad": None if follow is None else follow.theta_rad,
        "progress_m": None if follow is None else follow.s_m,
        "v_m_s": 0.0 if follow is None else follow.twist.v_m_s,
        "omega_rad_s": 0.0 if follow is None else follow.twist.omega_rad_s,
        "matched_points": matches,
        "inliers": vision.state.n_inliers if vision is not None else None,
        "lost": follow is not None and follow.lost is not None,
        "switch_reason": None if switch is None else switch.reason,
        "err_image_max_px": None if vision is None else vision.image_errors.err_image_max_px,
        "err_points_px": None if vision is None else vision.image_errors.err_points_px,
        "lateral_error_raw_m": vision.state.y_m if ok else None,
        "angular_error_raw_rad": vision.state.theta_rad if ok else None,
        "progress_raw_m": vision.state.s_m if ok else None,
        "compute_ms": record.compute_ns / 1e6,
    }


def event_line(event: AppEvent) -> tuple[str, str]:
    """The ``foxglove.Log`` level and text of a mission event."""
    return _EVENT_LEVELS.get(event.kind, "INFO"), f"{event.kind} {event.reason}: {event.detail}"


def note_level(level: int) -> str:
    """The ``foxglove.Log`` level of a ``logging`` level (CRITICAL becomes FATAL)."""
    return next((name for floor, name in _NOTE_LEVELS if level >= floor), "DEBUG")


class FieldLog:
    """The robot's field log (see the module docstring).

    Args:
        config: folder, frame rate, JPEG quality, ``replay_frames``, flushing, rotation.
        name: file name prefix, e.g. ``"robot"`` or ``"teach-east_a"``.
        mount: the camera's mount on the base (the static ``base_link`` -> ``camera``).
        run: key-value metadata ``run`` (robot, route, goal, git sha, ...).
        unix_offset_ns: Unix time minus the robot's clock reading, ns
            (:func:`shared.clock.unix_offset_ns`, measured once by the entry point).
    """

    def __init__(self, config: LogConfig, name: str, mount: CameraMountConfig,
                 run: Mapping[str, str], *, unix_offset_ns: int) -> None:
        self.config = config
        self._camera = camera_transform(mount)
        self._writer = LogWriter(config, name, unix_offset_ns=unix_offset_ns)
        self._writer.add_metadata(RUN_METADATA, {**run, SERIES_KEY: uuid.uuid4().hex})

    def mission_started(self, t_ns: int, goal_id: int, rng_state: Mapping[str, Any],
                        config: VmnavConfig) -> None:
        """A mission run to ``goal_id`` starts at ``t_ns``.

        Args:
            t_ns: the time given to ``MissionRun.start``, ns.
            goal_id: the goal key image.
            rng_state: the run's generator state before its first draw
                (``rng.bit_generator.state``; JSON-able, as ``default_rng``'s PCG64 is).
            config: the run's config (stored whole, ``dataclasses.asdict``).
        """
        self._writer.log_json(t_ns, topics.MISSION_START, "vmnav.MissionStart", {
            "stamp_ns": t_ns, "goal_key_image_id": goal_id, "rng_state": dict(rng_state),
            "config": dataclasses.asdict(config)})

    def cycle(self, record: CycleRecord, image: npt.NDArray[np.uint8]) -> None:
        """One mission cycle on its (H, W) uint8 grey frame.

        Args:
            record: what the cycle did.
            image: the frame the cycle consumed (copied when queued).
        """
        writer, t_ns, follow = self._writer, record.t_ns, record.follow
        state = servo_state(record)
        if writer.log_image(t_ns, topics.CAMERA_IMAGE, image,
                            lossless=self.config.replay_frames):
            # OpenCV's pixel centres are at integers, Foxglove's at +0.5 (messages.image_points).
            corners = np.zeros((0, 2)) if follow is None else follow.corners_xy + 0.5
            writer.log_points(t_ns, topics.CAMERA_ANNOTATIONS, corners,
                              label=frame_label(record.state.value, state["key_image_id"],
                                           state["matched_points"]))
        writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState", state)
        writer.log_json(t_ns, topics.BASE_STATE, "vmnav.BaseState",
                        base_state_fields(t_ns, record.base))
        if follow is not None:
            writer.log_json(t_ns, topics.CMD_VEL, "vmnav.Command", {
                "stamp_ns": t_ns, "linear_x_m_s": follow.twist.v_m_s,
                "angular_z_rad_s": follow.twist.omega_rad_s, "source": "servo"})
        self._odometry(t_ns, record.base.odom_pose)

    def event(self, event: AppEvent) -> None:
        """A mission event, as a ``foxglove.Log`` line at its time."""
        self._writer.log_text(event.t_ns, *event_line(event), EVENT_SOURCE)

    def note(self, t_ns: int, level: int, text: str) -> None:
        """A line for the operator (mode changes, paths saved, ...); ``level`` is a
        ``logging`` level (DEBUG ... CRITICAL, which becomes FATAL)."""
        self._writer.log_text(t_ns, note_level(level), text, NOTE_SOURCE)

    def pioneer_closed(self, t_ns: int, status: PioneerStatus, counters: LinkCounters) -> None:
        """How the Pioneer link ended, once the driver closed (stop and CLOSE sent), as a
        ``foxglove.Log`` line at ``t_ns``: the link state, the SIPs received and how long
        before ``t_ns`` the last came (with :meth:`sip` observing the driver, the last
        :data:`~shared.logs.topics.SIP` message), link losses, commands dropped, commands
        stopped by the driver's watchdog (the loop gave none in time).

        Args:
            t_ns: when the driver had closed, ns (the robot's clock).
            status: the driver's :meth:`~robot.pioneer.driver.PioneerDriver.status`.
            counters: the driver's :meth:`~robot.pioneer.driver.PioneerDriver.counters`.
        """
        last = ("" if status.last_sip_ns is None
                else f" (the last {(t_ns - status.last_sip_ns) / 1e6:.1f} ms before)")
        self._writer.log_text(
            t_ns, "INFO", f"pioneer {status.link.value.lower()}: {counters.sips} SIPs{last}; "
            f"{counters.link_losses} link losses, {counters.dropped_commands} commands dropped, "
            f"{counters.expired_commands} expired",
            PIONEER_SOURCE)

    def teach_frame(self, t_ns: int, image: npt.NDArray[np.uint8], odom_pose: Pose2) -> None:
        """A frame of a teach drive ((H, W) uint8 grey) with the odometry pose at its time."""
        self._writer.log_image(t_ns, topics.CAMERA_IMAGE, image)
        self._odometry(t_ns, odom_pose)

    def mavlink(self, t_ns: int, direction: str, packet: bytes) -> None:
        """A MAVLink packet received (``direction`` ``"in"``) or sent (``"out"``), whole."""
        self._writer.log_mavlink_packet(t_ns, packet, direction)

    def mavlink_rejected(self, t_ns: int, unverified: int, shed: int, period_ns: int) -> None:
        """MAVLink datagrams rejected over the ``period_ns`` before ``t_ns``, as one
        WARNING ``foxglove.Log`` line (counts only: an outsider cannot fill the log).

        Args:
            t_ns: the end of the period, ns.
            unverified: datagrams that held no verified message.
            shed: datagrams from strangers dropped unparsed under a flood.
            period_ns: the period's length, ns.
        """
        self._writer.log_text(
            t_ns, "WARNING", f"mavlink in: {unverified + shed} datagrams rejected in "
            f"{period_ns / 1e9:.1f} s ({unverified} without a verified message, {shed} shed "
            f"unparsed)", MAVLINK_SOURCE)

    def sip(self, t_ns: int, sip: Sip) -> None:
        """A SIP from the Pioneer, received at ``t_ns`` (a
        :class:`robot.pioneer.driver.PioneerDriver` SIP observer)."""
        self._writer.log_json(t_ns, topics.SIP, "vmnav.Sip", sip_fields(t_ns, sip))

    def stats(self) -> LogStats:
        """The writer's counters so far."""
        return self._writer.stats()

    def close(self) -> LogStats:
        """Write what is queued, finish the file; the writer's final counters. Idempotent."""
        return self._writer.close()

    def __enter__(self) -> FieldLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _odometry(self, t_ns: int, odom_pose: Pose2) -> None:
        self._writer.log_transform(t_ns, [
            FrameTransform.planar(topics.FRAME_ODOM, topics.FRAME_BASE, *odom_pose),
            self._camera])


def frame_label(state: str, key_id: int | None, matches: int) -> str:
    """The label drawn on a mission cycle's frame: the key image headed for (or the
    mission state) and the matches."""
    return (f"{state}: {matches} matches" if key_id is None
            else f"key {key_id}: {matches} matches")
