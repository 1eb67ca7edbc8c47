"""What the MAVLink vehicle endpoint needs from the robot application, and nothing more.

:class:`~robot.vehicle.endpoint.VehicleEndpoint` talks to the application only
through :class:`VehicleApp`: it reads one :class:`VehicleTelemetry` snapshot per
poll and turns ground-station requests into the calls below. The calls come from
whatever thread services the endpoint (the robot's loop, or the UDP thread of
:class:`~robot.vehicle.udp_vehicle.UdpVehicle`); an application serviced from
another thread must make them thread-safe. Each call returns at once: a request
the application cannot take now returns False (the ground station gets
``MAV_RESULT_DENIED``), and what happens next shows in the telemetry.

Units are SI, frames as in DESIGN.md sec. 4: the odometry frame has x forward,
y left, z up at the start of odometry; yaw is counter-clockwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Protocol

from robot.config import VmnavConfig
from robot.mission import MissionState
from shared.mavlink.mission.goal import Goal
from shared.mavlink.mission.items import MissionRefusal
from shared.mavlink.modes import Mode
from shared.pose import Pose2

#: What the robot does when the ground heartbeat stops: "stop" (MANUAL: stop driving),
#: "hold" (stop and wait in HOLD, mission kept), "continue" (carry on with the mission).
GcsLostAction = Literal["stop", "hold", "continue"]

#: Mission states in which the robot is working on a goal.
ACTIVE_STATES = frozenset({MissionState.LOCALIZING, MissionState.FOLLOWING, MissionState.LOST,
                           MissionState.WAITING})
#: The odometry frame's origin: the pose before the base reported any.
_ODOM_ORIGIN = Pose2(0.0, 0.0, 0.0)


#: The application's jobs that take a while and end with an outcome: finding a goal
#: photo in the memory (:meth:`VehicleApp.goto_image`), storing a taught path
#: (:meth:`VehicleApp.teach_stop`).
Job = Literal["photo", "path"]


@dataclass(frozen=True, slots=True)
class JobOutcome:
    """How a job (:data:`Job`) ended up.

    Attributes:
        job: which.
        value: what it made: the key image a photo was found at (now the goal), or the
            id of the path stored; None when it failed (a photo not found or unreadable,
            a path too short or not written) or was refused.
        text: one line for the operator, e.g. ``photo 3.jpg: key image 68: 61 matches, 52
            verified inliers (accepted), going there``.
    """

    job: Job
    value: int | None
    text: str


@dataclass(frozen=True, slots=True)
class ServoTelemetry:
    """The route follower's state (Courbon et al. 2008), for VISUAL_SERVO_STATUS.

    Attributes:
        current_key: key image the robot is at or last passed; None if none.
        next_key: key image being servoed to; None if none.
        matches: points matched between the current image and ``next_key``.
        err_image_max_px: largest image distance between matched points, px (NaN unknown).
        err_points_px: mean image distance between matched points, px (NaN unknown).
        y_m: lateral error to the line through the next key image, m, + left (NaN unknown).
        theta_rad: angular error to that line, rad, counter-clockwise (NaN unknown).
        s_m: along-track position relative to the next key image, m, negative before it.
    """

    current_key: int | None = None
    next_key: int | None = None
    matches: int = 0
    err_image_max_px: float = math.nan
    err_points_px: float = math.nan
    y_m: float = math.nan
    theta_rad: float = math.nan
    s_m: float = math.nan


@dataclass(frozen=True, slots=True)
class VehicleTelemetry:
    """One snapshot of the robot, for telemetry and mission progress.

    Attributes:
        mode: the mode the robot is in.
        armed: the motors accept commands.
        mission_state: the state of the current (or last) mission.
        mission_detail: one line on the last mission transition (its reason), for STATUSTEXT.
        teaching: a visual path is being recorded.
        battery_v: battery voltage, V (NaN unknown).
        odom_pose: the robot's pose in the odometry frame.
        velocity: (v_m_s forward, omega_rad_s counter-clockwise) in the robot frame.
        goal_key: goal key image of the current mission; None if none.
        servo: the follower's state while it runs; None otherwise.
        mission_seq: while the uploaded mission runs (or ran last), the seq of the item
            being driven to; None when the robot works on anything else (a photo goal).
        reached_seqs: mission items reached in the current run, in order; a run that
            starts again starts from ``()``.
        home_pose: the home's pose in the odometry frame (where the
            robot started); None while unknown.
        base_reporting: the mobile base's reports are current (``BaseState.reporting``).
        run_count: goal runs started so far (each goal of a mission is one run, a photo
            goal is one): a change tells a new run started, even when its states came
            and went between two snapshots the endpoint read.
        teach_thumbnails: while teaching, (id, PNG file) of each key image taken so far,
            in order: the id it gets when the path is stored, and its 80x60 thumbnail
            (served over FTP as ``/teaching/<id>.png``); () otherwise.
    """

    mode: Mode
    mission_state: MissionState = MissionState.IDLE
    armed: bool = False
    mission_detail: str = ""
    teaching: bool = False
    battery_v: float = math.nan
    odom_pose: Pose2 = _ODOM_ORIGIN
    velocity: tuple[float, float] = (0.0, 0.0)
    goal_key: int | None = None
    servo: ServoTelemetry | None = None
    mission_seq: int | None = None
    reached_seqs: tuple[int, ...] = ()
    home_pose: Pose2 | None = None
    base_reporting: bool = True
    run_count: int = 0
    teach_thumbnails: tuple[tuple[int, bytes], ...] = ()

    @property
    def mission_running(self) -> bool:
        """The uploaded mission runs now (AUTO and working on a goal)."""
        return self.mode is Mode.AUTO and self.mission_state in ACTIVE_STATES


class VehicleApp(Protocol):
    """The robot application as the vehicle endpoint sees it (module docstring)."""

    def telemetry(self) -> VehicleTelemetry:
        """The robot's state now."""
        ...

    def validate_goals(self, goals: tuple[Goal, ...]) -> MissionRefusal | None:
        """Check an uploaded mission: None accepts; a refusal (e.g. an unknown key image:
        ``MAV_MISSION_INVALID_PARAM1``; an unreachable goal) keeps the mission in force."""
        ...

    def set_mode(self, mode: Mode) -> bool:
        """Enter MANUAL, HOLD or GUIDED (AUTO goes through :meth:`start_mission`)."""
        ...

    def arm(self, armed: bool, force: bool) -> bool:
        """Enable (``armed``) or disable the motors; ``force`` skips the safety checks."""
        ...

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        """Enter AUTO and drive to ``goals`` in order; ``goals[0]`` is mission item
        ``first_seq`` (report progress in those seq numbers)."""
        ...

    def goto_image(self, path: Path) -> bool:
        """Localize the photo at ``path`` (uploaded over FTP) in the memory and go there;
        the outcome comes later from :meth:`next_job_outcome`."""
        ...

    def next_job_outcome(self) -> JobOutcome | None:
        """The oldest outcome of a job (:data:`Job`) not taken yet; None when none."""
        ...

    def params_changed(self, config: VmnavConfig) -> None:
        """Use ``config`` from now on (parameters set from the ground; already persisted)."""
        ...

    def manual_control(self, x: float, y: float, z: float, r: float, buttons: int,
                       now_ns: int) -> None:
        """A MANUAL_CONTROL from the ground station, axes normalized to [-1, 1] (NaN:
        axis not sent). MAVLink's body axes: ``x`` forward, ``y`` right, ``z`` thrust,
        ``r`` yaw, clockwise positive. ``buttons`` is the 16-bit button bitmask;
        ``now_ns`` when it arrived (for the application's dead-man stop)."""
        ...

    def teach_start(self, name: str) -> bool:
        """Start recording a visual path called ``name`` ("" lets the application pick)."""
        ...

    def teach_stop(self) -> bool:
        """Stop recording; the path joins the memory (the outcome comes later from
        :meth:`next_job_outcome`)."""
        ...

    def gcs_lost(self, action: GcsLostAction) -> None:
        """The ground heartbeat stopped: do ``action``."""
        ...

    def gcs_regained(self) -> None:
        """The ground heartbeat is back (the robot stays where ``gcs_lost`` left it)."""
        ...

    def next_notice(self) -> tuple[int, str] | None:
        """The oldest news for the operator not taken yet, as (``logging`` level, one line),
        e.g. a taught path saved or a photo not found in the memory; None when none."""
        ...
