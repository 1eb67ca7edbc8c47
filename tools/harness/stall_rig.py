"""A control loop that stalls while the robot drives, over real transports (issue 15, item 2).

The scene of the issue's hostile photo: the robot drives by hand, its loop hangs (in the
issue, decoding a bogus PNG) and the operator lets go of the stick. Only the command
watchdog of the Pioneer driver (``[pioneer] command_timeout_ns``) can stop the robot
then: the runtime's dead-man and camera-stall checks run on the stalled loop.

The parts, all real, in this process:

* the emulated Pioneer in the ``lab`` world's open corridor, served on a loopback TCP
  port in real time on a thread (as ``vmnav sim serve`` does), with a
  :class:`~tools.harness.hil_rig.TruthRecorder` on the simulation;
* the robot: a :class:`~robot.process.RobotProcess` (the runtime, its MAVLink endpoint
  on loopback UDP) on a :class:`~robot.pioneer.driver.PioneerDriver` connected to that
  port with its I/O thread, fed blank frames at 15 Hz on the wall clock
  (:class:`BlankFrames`: driving by hand uses no image);
* the operator: a MANUAL_CONTROL into the runtime on every frame, the stick giving
  ``speed_m_s``.

:func:`run_stall` drives for ``drive_s``, then blocks the loop thread inside its step for
``stall_s`` (the operator lets go at the same moment), lets the loop run ``settle_s``
more and reports what the simulation's truth saw (:class:`StallRun`). Times are in
simulation time, which the server keeps at the wall clock's pace (it lags on a starved
machine, and then runs slower than the driver's watchdog: figures are then optimistic).
"""

from __future__ import annotations

import contextlib
import dataclasses
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robot.camera import Frame, FrameStall
from robot.config import PioneerDriverConfig, VmnavConfig
from robot.mission_run import CycleRecord
from robot.pioneer.connection import CONNECT_TIMEOUT_S, why_not_connected
from robot.pioneer.driver import PioneerDriver
from robot.process import AfterStep, RobotParts, RobotProcess
from robot.vehicle.options import VehicleFiles
from shared.camera_model import CameraModel
from shared.clock import NS_PER_S, WallClock
from shared.errors import TransportError
from shared.mavlink.modes import Mode
from shared.memory import VisualMemory
from shared.pose import Pose2
from sim.config import SimConfig
from sim.pioneer import EmulatedPioneer, PioneerServer, TcpListener
from sim.simulation import Simulation
from sim.world import load_world
from tools.harness.hil_rig import STILL_M_S, TruthRecorder

#: Where the robot starts: the ``lab`` corridor, facing along it (metres of free floor ahead).
START = Pose2(8.0, 10.0, 0.0)
#: The camera's frame period, ns (15 frames/s, the simulator's and a typical webcam's).
FRAME_PERIOD_NS = NS_PER_S // 15
#: A speed this far below the speed at the stall means the base is braking, m/s (the
#: emulated Pioneer decelerates at 0.6 m/s², 0.006 m/s per 10 ms physics step).
BRAKING_M_S = 0.005


class BlankFrames:
    """A camera at :data:`FRAME_PERIOD_NS` on the wall clock whose frames are black
    (:class:`robot.process.TimedFrameSource`; the default camera's size)."""

    def __init__(self, clock: WallClock) -> None:
        self._clock = clock
        camera = CameraModel.default()
        self._image = np.zeros((camera.height, camera.width), np.uint8)
        self._next_ns = clock.now_ns()

    def read_within(self, timeout_ns: int) -> Frame | FrameStall | None:
        """The next frame at its time (never a stall: the period is below any timeout)."""
        self._next_ns = max(self._next_ns + FRAME_PERIOD_NS, self._clock.now_ns())
        self._clock.sleep_until_ns(self._next_ns)
        return self._clock.now_ns(), self._image


@dataclass(frozen=True, slots=True)
class StallRun:
    """What one stalled drive did, from the simulation's truth (times in simulation time).

    Attributes:
        speed_at_stall_m_s: the body's speed when the loop stalled, m/s.
        stop_after_stall_s: from the stall until the body began to brake (its speed
            :data:`BRAKING_M_S` below the speed at the stall), s: when the stop reached
            the base; None if it never braked during the stall.
        standstill_after_stall_s: from the stall until the body stood still (below
            ``hil_rig.STILL_M_S`` to the stall's end), s; None if it never did.
        distance_after_stall_m: path driven from the stall to the stall's end, m.
        distance_after_resume_m: path driven while the loop ran again afterwards, m (the
            operator had let go: the runtime's dead-man keeps the robot still).
        stall_s: how long the loop was blocked, s of simulation time.
        expired_commands: commands the driver's watchdog stopped.
    """

    speed_at_stall_m_s: float
    stop_after_stall_s: float | None
    standstill_after_stall_s: float | None
    distance_after_stall_m: float
    distance_after_resume_m: float
    stall_s: float
    expired_commands: int


@dataclass(frozen=True, slots=True)
class StallPlan:
    """The drive of :func:`run_stall`.

    Attributes:
        speed_m_s: the operator's speed, m/s (at most the teleop's full stick).
        drive_s: driving before the stall, s (the base reaches full speed in 0.7 s).
        stall_s: how long the loop blocks, s.
        settle_s: how long the loop runs after the stall, s.
        seed: the simulation's seed (sonar noise; the drive itself has no randomness).
        driver: the Pioneer driver's config (its ``url`` is replaced by the rig's port).
    """

    speed_m_s: float = 0.2
    drive_s: float = 2.0
    stall_s: float = 3.0
    settle_s: float = 1.0
    seed: int = 0
    driver: PioneerDriverConfig = field(default_factory=PioneerDriverConfig)


def run_stall(plan: StallPlan) -> StallRun:
    """Drive by hand over real TCP to the emulated Pioneer, stall the loop, report.

    Takes ``drive_s + stall_s + settle_s`` plus about a second to start.

    Raises:
        TransportError: the driver did not connect to the emulated Pioneer.
    """
    sim = Simulation(load_world("lab"), SimConfig(seed=plan.seed))
    sim.place_robot(START)
    truth = TruthRecorder(sim)
    sim.add_step_hook(truth)
    wall = WallClock()
    with contextlib.ExitStack() as stack:
        listener = stack.enter_context(contextlib.closing(TcpListener("127.0.0.1", 0)))
        server = PioneerServer(EmulatedPioneer(sim, sim.config.emulator,
                                               np.random.default_rng(plan.seed)),
                               links=[], listeners=[listener])
        stack.callback(server.close)
        thread = threading.Thread(target=server.run, args=(WallClock(),), name="stall-sim")
        thread.start()
        stack.callback(thread.join)
        stack.callback(server.stop)
        url = f"socket://127.0.0.1:{listener.port}"
        driver_config = dataclasses.replace(plan.driver, url=url)
        driver = stack.enter_context(PioneerDriver.from_config(driver_config, wall))
        driver.start_thread()
        if not driver.wait_connected(round(CONNECT_TIMEOUT_S * NS_PER_S)):
            raise TransportError(url, why_not_connected(driver))
        folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="vmnav-stall-")))
        config = VmnavConfig(pioneer=driver_config)
        files = VehicleFiles(folder / "memory", folder / "upload", folder / "params.parm")
        parts = RobotParts(VisualMemory(CameraModel.default()), driver, BlankFrames(wall), wall,
                           config, files, np.random.default_rng(plan.seed))
        robot = stack.enter_context(RobotProcess(parts, "udpin:127.0.0.1:0"))
        stick_x = plan.speed_m_s / config.teleop.max_speed_m_s
        marks: dict[str, int] = {}  # simulation times: stall, resume, end
        start_ns = wall.now_ns()

        def on_step(record: CycleRecord | None) -> AfterStep:
            """The operator on each frame; the stall inside the step that ends the drive."""
            elapsed_ns = wall.now_ns() - start_ns
            if "stall" not in marks:
                if elapsed_ns < plan.drive_s * NS_PER_S:
                    robot.runtime.manual_control(stick_x, np.nan, np.nan, 0.0, 0, 0)
                    return AfterStep.NEXT_FRAME
                marks["stall"] = sim.now_ns  # the operator lets go; the loop hangs
                wall.sleep_until_ns(wall.now_ns() + round(plan.stall_s * NS_PER_S))
                marks["resume"] = sim.now_ns
            if elapsed_ns < (plan.drive_s + plan.stall_s + plan.settle_s) * NS_PER_S:
                return AfterStep.NEXT_FRAME
            marks["end"] = sim.now_ns
            return AfterStep.STOP

        robot.runtime.set_mode(Mode.MANUAL)
        robot.run(on_step=on_step)
        expired = driver.counters().expired_commands
    return _measured(truth, marks["stall"], marks["resume"], marks["end"], expired)


def _measured(truth: TruthRecorder, stall_ns: int, resume_ns: int, end_ns: int,
              expired: int) -> StallRun:
    """The figures of :class:`StallRun` from the truth samples, simulation time in ns."""
    samples = truth.speeds(stall_ns, resume_ns)
    speed_at_stall = samples[0][1] if samples else 0.0
    braking = next((t for t, speed in samples if speed <= speed_at_stall - BRAKING_M_S), None)
    still: int | None = stall_ns  # the first sample from which the body stays still
    for t, speed in samples:
        if speed >= STILL_M_S:
            still = None
        elif still is None:
            still = t
    return StallRun(
        speed_at_stall_m_s=speed_at_stall,
        stop_after_stall_s=None if braking is None else (braking - stall_ns) / NS_PER_S,
        standstill_after_stall_s=None if still is None else (still - stall_ns) / NS_PER_S,
        distance_after_stall_m=truth.travelled_m(stall_ns, resume_ns),
        distance_after_resume_m=truth.travelled_m(resume_ns, end_ns),
        stall_s=(resume_ns - stall_ns) / NS_PER_S,
        expired_commands=expired,
    )
