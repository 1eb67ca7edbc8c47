"""The hardware-in-the-loop rig of the fault cases (:mod:`tools.harness.fault_cases`).

Three parts on real transports, as ``vmnav demo --hil`` runs them, except that the
simulator side lives in this process so that a case can reach its fault hooks and
its truth:

* :class:`SimSide`: the objects ``vmnav sim serve`` runs (the emulated Pioneer on a TCP
  port, the camera as MJPEG over HTTP, stepped in real time on a thread), with a
  :class:`TruthRecorder` on the simulation;
* ``vmnav robot`` as a subprocess on their URLs (:func:`start_robot`);
* a :class:`~ground.station.GroundStation` here, which the robot calls over UDP.

:func:`open_hil` starts the three on a copy of a taught memory (:class:`Taught`) and
stops them all however the block ends.

Times: the truth is in simulation time (ns), which runs at the wall clock's pace;
:attr:`SimSide.now_ns` marks when a fault was injected on that scale.
"""

from __future__ import annotations

import itertools
import math
import re
import shutil
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, closing, contextmanager
from dataclasses import dataclass
from pathlib import Path

from ground.fleet import VehicleState
from ground.station import GroundStation
from robot.config import VmnavConfig
from shared.calibration import load_camera
from shared.clock import NS_PER_S, WallClock
from shared.mavlink.mission.goal import Goal
from sim.camera_server import CameraServer
from sim.config import SimConfig
from sim.pioneer import TcpListener
from sim.pioneer.world_server import pioneer_server
from sim.simulation import Simulation
from tools.harness.short_routes import teach_east_a
from tools.harness.teach import TaughtMemory
from tools.harness.vmnav_process import VmnavProcess

#: How long ``vmnav robot`` may take to start, and then to answer the ground station, s
#: (about 3 s on an idle machine; a starved one takes many times that to import and load).
ROBOT_START_S = 120.0
#: What ``vmnav robot`` prints once its memory is loaded and its links serve (its MAVLink
#: thread runs, so a HEARTBEAT may come before it).
ROBOT_STARTED = re.compile(r"^vmnav robot: .*; memory .*: \d+ paths, \d+ key images$", re.M)
#: How long a mission may take to drive its first metres, s (2 s at 0.2 m/s on an idle
#: machine; a starved robot localizes and steers late, and its simulation lags).
START_DRIVING_S = 60.0
#: SIGTERM, then SIGKILL after this long, s.
STOP_GRACE_S = 15.0
#: Below these the robot's body counts as standing still: m/s, rad/s.
STILL_M_S = 0.01
STILL_RAD_S = 0.02
_POLL_NS = 20_000_000
#: The simulation not advancing for this long means its loop hangs, s (it lags the wall
#: clock on a loaded machine, but keeps moving).
SIM_STUCK_S = 10.0


class FaultCaseError(AssertionError):
    """A fault case saw other behaviour than expected (one line)."""


def expect(condition: bool, message: str) -> None:
    """Raise :class:`FaultCaseError` with ``message`` unless ``condition``."""
    if not condition:
        raise FaultCaseError(message)


def wait_until(done: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll ``done()`` on the wall clock every 20 ms, at most ``timeout_s``.

    Raises:
        FaultCaseError: not done in time (``what`` says what was awaited).
    """
    clock = WallClock()
    limit_ns = clock.now_ns() + round(timeout_s * NS_PER_S)
    while not done():
        expect(clock.now_ns() < limit_ns, f"{what}: not within {timeout_s:g} s")
        clock.sleep_until_ns(clock.now_ns() + _POLL_NS)


@dataclass(frozen=True, slots=True)
class Taught:
    """The ``east_a`` route of :mod:`tools.harness.short_routes`, taught in lock-step (seed 1).

    Attributes:
        world_file: the world TOML (the lab plus the short routes).
        memory_dir: the taught memory; cases work on copies.
        taught: the memory (one path) and the true poses of its key images.
    """

    world_file: Path
    memory_dir: Path
    taught: TaughtMemory

    @property
    def keyframe_ids(self) -> tuple[int, ...]:
        """The path's key images in order."""
        (path_id,) = self.taught.path_ids
        return tuple(self.taught.memory.paths[path_id].keyframe_ids)

    @property
    def goal_xy(self) -> dict[int, tuple[float, float]]:
        """Key image id -> where it was taken, world frame (x_m, y_m), from the true poses."""
        return {key: (pose.x_m, pose.y_m) for key, pose in self.taught.true_poses.items()}


def teach(folder: Path) -> Taught:
    """Teach ``east_a`` into ``folder/memory`` (about 4 s; ``folder`` is made if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    world_file, taught = teach_east_a(folder, VmnavConfig())
    return Taught(world_file, folder / "memory", taught)


class TruthRecorder:
    """The body's true speed and position at every physics step.

    A step hook (called in the simulation's thread); read from any thread.
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._lock = threading.Lock()
        self._t_ns: list[int] = []
        self._motion: list[tuple[float, float]] = []  # (speed m/s, |turn rate| rad/s)
        self._xy: list[tuple[float, float]] = []

    def __call__(self, now_ns: int, dt_ns: int) -> None:
        vx, vy, omega = self._sim.body.velocity_base
        x, y, _ = self._sim.body.pose_w
        with self._lock:
            self._t_ns.append(now_ns)
            self._motion.append((math.hypot(vx, vy), abs(omega)))
            self._xy.append((x, y))

    def moved_m(self) -> float:
        """Straight-line distance from the first sample to the last, m."""
        with self._lock:
            if not self._xy:
                return 0.0
            (x0, y0), (x1, y1) = self._xy[0], self._xy[-1]
        return math.hypot(x1 - x0, y1 - y0)

    def position(self) -> tuple[float, float]:
        """The last position sampled, world frame, m."""
        with self._lock:
            return self._xy[-1]

    def motion(self, t0_ns: int, t1_ns: int) -> tuple[float, float]:
        """The largest speed (m/s) and turn rate (rad/s) sampled in ``[t0_ns, t1_ns]``.

        Raises:
            FaultCaseError: no sample there (the simulation has not got that far).
        """
        with self._lock:
            inside = [m for t, m in zip(self._t_ns, self._motion, strict=True)
                      if t0_ns <= t <= t1_ns]
        expect(bool(inside), f"no truth between {t0_ns / 1e9:.2f} and {t1_ns / 1e9:.2f} s")
        return max(s for s, _ in inside), max(w for _, w in inside)

    def speeds(self, t0_ns: int, t1_ns: int) -> list[tuple[int, float]]:
        """``(t_ns, speed m/s)`` of every sample in ``[t0_ns, t1_ns]``, in time order."""
        with self._lock:
            return [(t, speed) for t, (speed, _) in zip(self._t_ns, self._motion, strict=True)
                    if t0_ns <= t <= t1_ns]

    def travelled_m(self, t0_ns: int, t1_ns: int) -> float:
        """Path length driven in ``[t0_ns, t1_ns]``, m."""
        with self._lock:
            xy = [p for t, p in zip(self._t_ns, self._xy, strict=True) if t0_ns <= t <= t1_ns]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(xy))

    def still(self, t0_ns: int, t1_ns: int) -> str | None:
        """None if the body stood still throughout ``[t0_ns, t1_ns]``; else what moved."""
        speed, turn = self.motion(t0_ns, t1_ns)
        if speed < STILL_M_S and turn < STILL_RAD_S:
            return None
        return (f"moving between {t0_ns / 1e9:.2f} and {t1_ns / 1e9:.2f} s "
                f"(up to {speed:.3f} m/s, {turn:.3f} rad/s)")


class SimSide:
    """``vmnav sim serve``'s objects in this process (built by the same
    :func:`sim.pioneer.world_server.pioneer_server`): the world in real time on a thread, the
    emulated Pioneer on a TCP port and the camera on HTTP (ports picked free), with their
    fault hooks at hand.

    Args:
        world_file: the world.
        seed: the simulation's seed (the emulator draws from its child, as sim serve's).

    Attributes:
        sim, emulator, server, camera: the parts; ``server`` and ``camera`` hold the
            fault hooks (``cut``, ``inject``; ``stall``, ``corrupt``).
        truth: the body's true motion.
        aria_url: the ARIA server for ``--aria`` (``socket://127.0.0.1:PORT``).
    """

    def __init__(self, world_file: Path, seed: int = 1) -> None:
        config = SimConfig(world=str(world_file), seed=seed,  # the robot's default mount
                           camera_mount=VmnavConfig().camera.mount)
        with ExitStack() as opened:
            listener = opened.enter_context(closing(TcpListener("127.0.0.1", 0)))
            self.camera = opened.enter_context(CameraServer("127.0.0.1", 0))
            self.server = opened.enter_context(pioneer_server(
                config, load_camera(config.camera_file), [], [listener], self.camera))
            self.emulator = self.server.emulator
            self.sim = self.emulator.simulation
            self.truth = TruthRecorder(self.sim)
            self.sim.add_step_hook(self.truth)
            self.aria_url = f"socket://127.0.0.1:{listener.port}"
            self._thread = threading.Thread(target=self.server.run, args=(WallClock(),),
                                            name="sim-side")
            self._thread.start()
            self._opened = opened.pop_all()

    @property
    def now_ns(self) -> int:
        """Simulation time now, ns."""
        return self.sim.now_ns

    @property
    def running(self) -> bool:
        """The simulation loop is alive."""
        return self._thread.is_alive()

    def close(self) -> None:
        """Stop the loop, then close the server and the camera; idempotent."""
        self.server.stop()
        self._thread.join()
        self._opened.close()

    def __enter__(self) -> SimSide:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def start_robot(sim: SimSide, station: GroundStation | int, folder: Path,
                out_name: str, extra: Sequence[str] = ()) -> VmnavProcess:
    """``vmnav robot`` on the rig's transports, with ``folder``'s ``memory``, ``state`` and
    ``logs`` (the field log, as on the robot), its output in ``folder/out_name``; stopped
    by SIGTERM, SIGKILL after :data:`STOP_GRACE_S`. It sends MAVLink to ``station``'s UDP
    port on 127.0.0.1, or to that port given as a number (a station in another process:
    ``vmnav ground web``). ``extra``: more ``vmnav robot`` options (``--video``)."""
    port = station if isinstance(station, int) else station.link.local_port
    argv = ["robot", "--aria", sim.aria_url, "--camera", sim.camera.stream_url,
            "--mavlink", f"udpout:127.0.0.1:{port}",
            "--memory", str(folder / "memory"), "--state", str(folder / "state"),
            "--log", str(folder / "logs"), *extra]
    return VmnavProcess(argv, folder / out_name, STOP_GRACE_S)


@dataclass(eq=False)
class Hil:
    """A running rig (:func:`open_hil`).

    Attributes:
        sim: the simulator side.
        station: the ground station, aimed at the robot.
        robot: the robot process (the last one started).
        folder: the case's folder: ``memory``, ``state``, ``logs``, the robot's output.
    """

    sim: SimSide
    station: GroundStation
    robot: VmnavProcess
    folder: Path

    def restart_robot(self, out_name: str) -> None:
        """Start ``vmnav robot`` again (after the last one ended) with output in
        ``folder/out_name``, and wait until it answers (:meth:`wait_robot`)."""
        self.robot = start_robot(self.sim, self.station, self.folder, out_name)
        self.wait_robot()

    def wait_robot(self) -> None:
        """Wait until the robot prints its start line (:data:`ROBOT_STARTED`), then for a
        HEARTBEAT received after that, and aim the station at the robot.

        Ordered so that neither can come from an earlier robot: the station is serviced
        while the robot starts, so a packet a killed robot left in the socket is read (and
        stamped) before the wait for the HEARTBEAT begins. Each wait ends early when the
        robot ends.

        Raises:
            FaultCaseError: no start line or no HEARTBEAT within :data:`ROBOT_START_S` each,
                or the robot ended first (with its last line of output).
        """
        def ended() -> bool:
            return self.robot.process.poll() is not None

        def started() -> bool:
            return ROBOT_STARTED.search(self.robot.output()) is not None

        limit_ns = round(ROBOT_START_S * NS_PER_S)
        self.station.run_until(lambda: started() or ended(), limit_ns)
        expect(started(), f"vmnav robot did not start: {self.robot.last_line()}")
        since_ns = self.station.clock.now_ns()

        def answered() -> bool:
            return any(v.last_heartbeat_ns >= since_ns
                       for v in self.station.fleet.vehicles.values())

        self.station.run_until(lambda: answered() or ended(), limit_ns)
        expect(answered(), f"vmnav robot did not answer: {self.robot.last_line()}")
        self.station.wait_vehicle(1.0)

    def run_until(self, done: Callable[[], bool], timeout_s: float, what: str) -> None:
        """Service the station until ``done()``, at most ``timeout_s``.

        Raises:
            FaultCaseError: not done in time (``what`` says what was awaited).
        """
        expect(self.station.run_until(done, round(timeout_s * NS_PER_S)),
               f"{what}: not within {timeout_s:g} s")

    def wait_sim(self, until_ns: int) -> None:
        """Service the station until the simulation reaches ``until_ns``, however long that
        takes on the wall clock while the simulation advances.

        Raises:
            FaultCaseError: the simulation did not advance for :data:`SIM_STUCK_S`.
        """
        def advanced(since_ns: int) -> bool:
            return self.sim.now_ns > since_ns

        while (now_ns := self.sim.now_ns) < until_ns:
            self.run_until(lambda since_ns=now_ns: advanced(since_ns), SIM_STUCK_S,
                           f"simulation time {until_ns / NS_PER_S:.1f} s (stuck at "
                           f"{now_ns / NS_PER_S:.1f} s)")

    @property
    def vehicle(self) -> VehicleState:
        """The robot as the station knows it."""
        vehicle = self.station.vehicle
        if vehicle is None:
            raise FaultCaseError("the ground station has no vehicle")
        return vehicle

    def notices(self) -> list[str]:
        """The robot's STATUSTEXT notices so far."""
        return list(self.vehicle.notices)

    def notice(self, pattern: str, since: int = 0) -> re.Match[str] | None:
        """The first of the robot's notices from number ``since`` on (0: the first) that
        matches the regular expression ``pattern``.

        ``since=len(hil.notices())`` taken when a fault is injected looks only at what the
        robot said after it: a loaded machine can make the robot report a stall or a lost
        link of its own before the fault, and that notice does not answer for the fault.
        """
        return next((m for n in self.notices()[since:] if (m := re.search(pattern, n))), None)

    def start_goal(self, goal: int, drive_m: float) -> None:
        """Upload a one-goal mission to key image ``goal``, start it, and wait until the robot
        has driven ``drive_m`` (it is following the route by then)."""
        self.station.upload_goals([Goal(goal)])
        self.station.start_mission()
        self.run_until(lambda: self.sim.truth.moved_m() >= drive_m, START_DRIVING_S,
                       f"driving {drive_m} m towards key image {goal}")

    def reach(self, taught: Taught, goal: int, timeout_s: float, tolerance_m: float) -> None:
        """Wait until the mission reaches key image ``goal``; check the robot stands within
        ``tolerance_m`` of where the key image was taken.

        Raises:
            FaultCaseError: not reached in ``timeout_s``, or reached elsewhere.
        """
        reached = self.station.wait_mission_done(timeout_s)
        expect(reached, f"key image {goal} not reached (outcome {self.station.mission_outcome});"
                        f" notices {self.notices()}")
        (x, y), (gx, gy) = self.sim.truth.position(), taught.goal_xy[goal]
        error = math.hypot(x - gx, y - gy)
        expect(error <= tolerance_m, f"ended {error:.3f} m from key image {goal} "
                                     f"(tolerance {tolerance_m} m)")


@contextmanager
def open_hil(taught: Taught, folder: Path) -> Iterator[Hil]:
    """The rig on a copy of ``taught``'s memory in ``folder/memory``: the robot started
    (:func:`start_robot`), its output in ``folder/robot.out``, and answering.
    Everything is stopped after, however the block ends (the robot by SIGTERM).

    Raises:
        FaultCaseError: the robot did not answer.
    """
    shutil.copytree(taught.memory_dir, folder / "memory")
    with ExitStack() as stack:
        sim = stack.enter_context(SimSide(taught.world_file))
        station = stack.enter_context(GroundStation.open("udpin:127.0.0.1:0", WallClock()))
        robot = start_robot(sim, station, folder, "robot.out")
        hil = Hil(sim, station, robot, folder)
        stack.callback(lambda: hil.robot.stop())
        hil.wait_robot()
        yield hil
