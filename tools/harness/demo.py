"""``vmnav demo``: the whole teach-and-repeat story in the simulator, in lock-step, one process.

It couples the simulator and the robot application, so it lives in the harness (tools/harness/):

1. **Teach** (:func:`taught_memory`): the routes of the world are driven by the
   scripted teach driver and stored, joined, into one visual memory in ``OUT/memory``
   (:func:`tools.harness.teach.teach_memory`); the true poses of the key images go to
   ``OUT/teach.json`` for the evaluation. A memory already there, taught in the same
   world with the same seed, routes and camera, is reused; a memory there taught
   otherwise is an error (never overwritten).
2. **Repeat** (:func:`repeat_in_sim`): a fresh simulation of the world as it is on
   the day of the repeat (optionally with people, other light and objects moved:
   :mod:`sim.scene_change`), the robot placed off the taught path: the robot process
   (:class:`robot.process.RobotProcess`, as on the robot) on
   :class:`sim.sim_camera.SimFrameSource`, the ARIA driver of the emulated Pioneer
   (:func:`tools.harness.lockstep_pioneer.lockstep_pioneer`) and
   :class:`sim.sim_clock.SimClock`, as a MAVLink vehicle on loopback UDP. A ground
   station (:class:`tools.harness.ground_dispatch.GroundDispatch`) sends the goal, a key
   image on another path, as a one-item mission and starts it (AUTO), while the
   simulation's clock is held; the robot localizes, plans and follows until it stops in
   HOLD. Each mission cycle is recorded with the ground truth.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from ground.station import GroundError
from shared.errors import InputError
from shared.pose import Pose2

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.field_log import FieldLog
    from robot.mission_run import CycleRecord, MissionResult
    from robot.process import AfterStep
    from robot.runtime import RobotRuntime
    from shared.camera_model import CameraModel
    from shared.clock import Clock
    from shared.memory import VisualMemory
    from sim.config import SimConfig
    from sim.renderer import RenderedFrame
    from sim.scene_change import ChangedWorld, SceneChange
    from sim.sim_camera import SimFrameSource
    from sim.simulation import Simulation
    from sim.world import World
    from tools.harness.ground_dispatch import DispatchResult
    from tools.harness.teach import TaughtMemory

#: Start offset from the taught path: left of it, m, and turned, degrees (issue 4).
START_OFFSET_M = 0.3
START_OFFSET_DEG = 10.0
#: The start is this key image of the first route (ahead of it the path is straight).
START_KEY_INDEX = 2
#: Mixed with the seed for the repeat's random draws (RANSAC, the Pioneer's noise).
_REPEAT_STREAM = 0x52455045
#: Mixed with the seed for the scene change's draws (which objects move, and where), so
#: that a change leaves the repeat's other draws alone.
_CHANGE_STREAM = 0x4348414E
#: The ground station must have dispatched the goal within this wall time, s.
_DISPATCH_TIMEOUT_S = 20.0
#: After the robot stopped, the ground station has this long to see the outcome, s (it
#: comes with the next telemetry, at most one status period later).
_OUTCOME_GRACE_S = 5.0
#: The operator stops the mission after this many times the route's length at the servo
#: speed, plus ``_EXTRA_S``.
_TIME_MARGIN = 3.0
_EXTRA_S = 30.0


@dataclass(frozen=True, eq=False)
class CycleSample:
    """One servo cycle with its ground truth.

    Attributes:
        record: what the application did.
        pose_w: true robot pose (x_m, y_m, yaw_rad) at the frame.
    """

    record: CycleRecord
    pose_w: Pose2


@dataclass(frozen=True, eq=False)
class RepeatRun:
    """A repeat: the mission's result, every cycle, and what the ground station saw."""

    result: MissionResult
    start_pose: Pose2
    goal_id: int
    samples: tuple[CycleSample, ...]
    sim_time_s: float
    dispatch: DispatchResult
    changed: ChangedWorld
    start_offset_m: float = START_OFFSET_M


def taught_memory(out: Path, routes: tuple[str, ...] | None, config: VmnavConfig,
                  sim_config: SimConfig, camera: CameraModel,
                  processes: int | None = None) -> TaughtMemory:
    """Teach ``routes``, joined, into ``out/memory`` (or reuse the memory taught there
    before: :func:`tools.harness.teach.teach_memory` with ``folder=out``).

    Args:
        out: the output folder.
        routes: route names in teaching order; None: all the world's routes in the
            order its file lists them (the order that joins them, e.g. the lab's
            corridor, office_loop, north_loop).
        config: teach, features and localization settings.
        sim_config: the world and seed (people are left out while teaching).
        camera: the simulated camera.
        processes: processes the routes are driven in (None: one per CPU, see
            :func:`tools.harness.teach.teach_memory`).

    Raises:
        InputError: an unknown route, a route the teach driver could not finish, or a
            memory in ``out/memory`` taught otherwise.
        MemoryFormatError: ``out/memory`` holds files but no manifest, or a memory that
            does not load.
    """
    from sim.world import load_world
    from tools.harness.teach import teach_memory

    teach_config = replace(sim_config, people=replace(sim_config.people, count=0))
    return teach_memory(load_world(sim_config.world), routes, config, teach_config, camera,
                        join=True, folder=out, processes=processes)


def follow_config(config: VmnavConfig, law: str | None = None,
                  max_omega_deg: float | None = None,
                  speed_m_s: float | None = None) -> VmnavConfig:
    """``config`` with another control law, turn-rate bound (deg/s) and servo speed (m/s);
    None keeps the config's (the robot's defaults, ``robot.config.ControlConfig``).

    Raises:
        InputError: ``max_omega_deg`` is not > 0.
        ConfigError: an unknown law, a speed out of the config's range.
    """
    control = config.control
    if law is not None:
        control = replace(control, law=law)
    if speed_m_s is not None:
        control = replace(control, speed_m_s=speed_m_s)
    if max_omega_deg is not None:
        if not max_omega_deg > 0:
            raise InputError("--max-omega-deg", f"must be > 0, got {max_omega_deg}")
        control = replace(control, max_omega_rad_s=math.radians(max_omega_deg))
    return replace(config, control=control)


def default_goal(taught: TaughtMemory) -> int:
    """The middle key image of the second path taught (the last key image of a lone path)."""
    paths = taught.memory.paths
    if len(taught.path_ids) == 1:
        return paths[taught.path_ids[0]].keyframe_ids[-1]
    ids = paths[taught.path_ids[1]].keyframe_ids
    return ids[len(ids) // 2]


def start_pose(taught: TaughtMemory, offset_m: float = START_OFFSET_M) -> Pose2:
    """Off the first path at its key image ``START_KEY_INDEX``: shifted ``offset_m`` to the
    left (negative: right) and turned ``START_OFFSET_DEG``."""
    ids = taught.memory.paths[taught.path_ids[0]].keyframe_ids
    x, y, yaw = taught.true_poses[ids[min(START_KEY_INDEX, len(ids) - 1)]]
    return Pose2(x - offset_m * math.sin(yaw), y + offset_m * math.cos(yaw),
                 yaw + math.radians(START_OFFSET_DEG))


def check_goal(memory: VisualMemory, goal_id: int) -> None:
    """Raise unless ``goal_id`` is a key image of ``memory``.

    Raises:
        InputError: one line naming ``--goal`` and the memory's ids.
    """
    if goal_id not in memory.keyframes:
        raise InputError("--goal", f"key image {goal_id} is not in the memory "
                                   f"(ids 0..{max(memory.keyframes)})")


def repeat_in_sim(taught: TaughtMemory, goal_id: int, config: VmnavConfig,
                  sim_config: SimConfig, change: SceneChange, out: Path,
                  on_cycle: Callable[[Simulation, RenderedFrame, CycleSample], None] | None = None,
                  robot_log: FieldLog | None = None, ground_log: Path | None = None,
                  on_sim: Callable[[Simulation], None] | None = None,
                  start_offset_m: float = START_OFFSET_M,
                  vehicle_dir: Path | None = None) -> RepeatRun:
    """Place the robot, dispatch the goal from the ground station, and let the robot
    localize, plan and follow (see the module docstring), computing on every CPU but one
    (:func:`tools.threads.leave_a_cpu`: never on more threads than were set).

    Args:
        taught: the memory and its truth.
        goal_id: the goal key image.
        config: the robot's configs.
        sim_config: the repeat's simulation (people, seed, world).
        change: what changed since the teach (light, objects moved); the people are
            ``sim_config.people``.
        out: the output folder (the memory is ``out/memory``); the vehicle keeps its
            parameters and uploads in ``out/vehicle`` (parameters start from ``config`` on
            every run).
        on_cycle: called after each mission cycle with the simulation and the frame (video).
        robot_log: the robot's field log (missions, cycles, events, notes, its MAVLink
            traffic stamped on the simulation clock), finished when the repeat ends;
            None: no robot log.
        ground_log: the ground station's log folder; None: no ground log.
        on_sim: called with the repeat's simulation once the robot is placed (a
            benchmark's truth: step hooks).
        start_offset_m: the start's shift left of the first path, m (:func:`start_pose`).
        vehicle_dir: the vehicle's folder instead of ``out/vehicle`` (repeats of one
            memory running at once each need their own).

    Raises:
        InputError: ``goal_id`` is not a key image of the memory, the start
            pose overlaps an obstacle, or ``change`` does not fit the world.
        GroundError: the ground station could not dispatch the goal.
    """
    import numpy as np

    from robot.process import RobotParts, RobotProcess
    from robot.vehicle.options import VehicleFiles
    from shared.clock import WallClock
    from sim.sim_camera import SimFrameSource
    from sim.sim_clock import SimClock
    from sim.simulation import Simulation
    from sim.world import load_world
    from tools.harness.ground_dispatch import GroundDispatch
    from tools.harness.lockstep_pioneer import lockstep_pioneer
    from tools.threads import leave_a_cpu

    memory = taught.memory
    check_goal(memory, goal_id)
    # Every CPU but one: beside the lock-step loop run ffmpeg (the demo's video) and the
    # ground station, and idle render threads spin while the robot's loop runs between
    # frames (`make demo`'s repeat, 2026-11-30, idle 2-core machine: 101 s of wall time on
    # two render threads, 84 s on one; without video, 62 and 59 s).
    leave_a_cpu()
    rng = np.random.default_rng([sim_config.seed, _REPEAT_STREAM])
    start = start_pose(taught, start_offset_m)
    taught_world = load_world(sim_config.world)
    changed = changed_world(taught_world, change, sim_config.seed, (start.x_m, start.y_m))
    sim = Simulation(changed.world, sim_config, landmark_world=taught_world)
    sim.light_gain_at = change.lighting.gain_at
    sim.place_robot(start)
    if on_sim is not None:
        on_sim(sim)
    clock = SimClock(sim)
    base, _ = lockstep_pioneer(clock, config.pioneer, rng)
    frames = SimFrameSource(sim, memory.camera, clock)
    vehicle = out / "vehicle" if vehicle_dir is None else vehicle_dir
    files = VehicleFiles(out / "memory", vehicle / "upload", vehicle / "params.parm")
    files.param_file.unlink(missing_ok=True)
    taught_m = sum(memory.keyframes[p.keyframe_ids[-1]].distance_m
                   for p in memory.paths.values())
    limit_ns = round((_TIME_MARGIN * taught_m / config.control.speed_m_s + _EXTRA_S) * 1e9)
    wall = WallClock()
    parts = RobotParts(memory, base, frames, clock, config, files, rng, log=robot_log,
                       lockstep=True)
    with RobotProcess(parts, "udpin:127.0.0.1:0", link_clock=wall) as robot:
        ground = GroundDispatch(f"udpout:127.0.0.1:{robot.vehicle.link.local_port}", goal_id,
                                _DISPATCH_TIMEOUT_S + limit_ns / 1e9, ground_log)
        ground.start()
        watch = _RepeatWatch(robot.runtime, sim, frames, wall, limit_ns, on_cycle)
        robot.run(period_ns=sim_config.frame_period_ns, on_step=watch.on_step)
        dispatch = ground.finish(_OUTCOME_GRACE_S)
    result = robot.runtime.last_result
    if result is None:
        raise GroundError(dispatch.error or f"the ground station dispatched no goal in "
                                            f"{_DISPATCH_TIMEOUT_S:.0f} s")
    return RepeatRun(result=result, start_pose=start, goal_id=goal_id,
                     samples=tuple(watch.samples), sim_time_s=sim.now_ns / 1e9,
                     dispatch=dispatch, changed=changed, start_offset_m=start_offset_m)


def changed_world(world: World, change: SceneChange, seed: int,
                  keep_clear_xy: tuple[float, float] | None = None) -> ChangedWorld:
    """The repeat's world: ``world`` after ``change``, drawn from the seed's scene-change
    stream (so that the change leaves the repeat's other draws alone).

    Called before teaching too, with no point kept clear, so that a change the world
    cannot take is refused before minutes of teaching.

    Args:
        world: the world as taught.
        change: what changed.
        seed: the simulation's seed.
        keep_clear_xy: (x, y) no moved object may come near (the repeat's start), m.

    Raises:
        InputError: the change does not fit the world (one line naming what).
    """
    import numpy as np

    from sim.scene_change import change_world

    keep = None if keep_clear_xy is None else np.array([keep_clear_xy], dtype=float)
    try:
        return change_world(world, change, np.random.default_rng([seed, _CHANGE_STREAM]), keep)
    except ValueError as e:
        raise InputError("scene change", str(e)) from None


class _RepeatWatch:
    """The repeat's ``on_step`` (:class:`robot.process.RobotProcess`): each mission cycle
    with its ground truth, and the operator's stop conditions.

    Until the ground station has started the mission (AUTO), the simulation's clock is
    held (:attr:`~robot.process.AfterStep.HOLD_CLOCK`): the mission starts on the same
    frame however fast the ground station answers, and every run gives the same figures.
    The repeat ends when the robot is back in HOLD, or when the ground station has not
    started the mission within :data:`_DISPATCH_TIMEOUT_S` (wall time); it
    ends the mission (HOLD, cause ``time_limit``) after ``limit_ns`` of simulated time.
    """

    def __init__(self, runtime: RobotRuntime, sim: Simulation, frames: SimFrameSource,
                 wall: Clock, limit_ns: int,
                 on_cycle: Callable[[Simulation, RenderedFrame, CycleSample], None] | None
                 ) -> None:
        self._runtime = runtime
        self._sim = sim
        self._frames = frames
        self._wall = wall
        self._limit_ns = limit_ns
        self._on_cycle = on_cycle
        self._wait_until_ns = wall.now_ns() + round(_DISPATCH_TIMEOUT_S * 1e9)
        self._started_ns: int | None = None
        self.samples: list[CycleSample] = []

    def on_step(self, record: CycleRecord | None) -> AfterStep:
        """Record the cycle (``record``: None when no mission run drove); what the loop
        does next."""
        from robot.process import AfterStep
        from shared.mavlink.modes import Mode

        if record is not None:
            sample = CycleSample(record=record, pose_w=self._sim.body.pose_w)
            self.samples.append(sample)
            if self._on_cycle is not None and self._frames.last is not None:
                self._on_cycle(self._sim, self._frames.last, sample)
        mode = self._runtime.telemetry().mode
        if self._started_ns is None:
            if mode is Mode.AUTO:
                self._started_ns = self._sim.now_ns
                return AfterStep.NEXT_FRAME
            if self._wall.now_ns() > self._wait_until_ns:
                return AfterStep.STOP
            return AfterStep.HOLD_CLOCK
        if mode is Mode.HOLD:
            return AfterStep.STOP
        if self._sim.now_ns - self._started_ns > self._limit_ns:
            self._runtime.time_limit(f"time limit {self._limit_ns / 1e9:.0f} s of simulated "
                                     "time reached")
        return AfterStep.NEXT_FRAME
