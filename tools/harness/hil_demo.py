"""``vmnav demo --hil``: the teach-and-repeat story as the field runs it, in separate processes.

Three processes on real transports:

* ``vmnav sim serve``: the world in real time, the emulated Pioneer on TCP, the camera
  as MJPEG over HTTP, and the simulator's control endpoint (``sim.control_server``:
  the true pose, and placing the robot);
* ``vmnav robot``: the robot process on those URLs, with the memory, parameters and
  field log in ``OUT/``, calling the ground station over UDP;
* this process, the ground station (:class:`ground.station.GroundStation`, logged to
  ``OUT/logs``), with a scripted operator.

The story (:func:`run_hil`):

1. The robot is placed at the start of the world's first route; the operator starts
   teaching over the link and drives the route by MANUAL_CONTROL at 10 Hz, steering
   by the true pose as a person steers by eye (:class:`sim.teach_driver.TeachDriver`,
   as the lock-step demo's teacher); teach stop makes the robot store the path.
2. The robot is carried 0.3 m left of the taught drive and turned 10 degrees, at the
   lock-step demo's start key image; the ground station dispatches the path's last key
   image as a one-goal mission and starts it; the robot localizes, plans and follows.
3. Evaluation from the truth: the repeat's true trajectory against the teach's (lateral
   and heading errors after the same settling distance as the lock-step demo), the
   final position error against the teach's end, the mission's outcome as the ground
   station saw it; from the robot's field log: key images reached, mean matches, LOST
   events. ``OUT/report.json`` holds it all.

With ``--web`` (``watch``), this process also serves the web app on loopback
(``vmnav ground web``'s :class:`~ground.web.server.WebServer`, a free port, its URL
announced) and the robot serves its camera (``--video``): a user watches the story in a
browser, and may click (Hold, the emergency stop). The web app's loop then owns the
ground station and the operator's steps go through it
(:class:`~tools.harness.station_hands.StationHands`).

Every process is stopped (SIGTERM, then SIGKILL after a grace period) on success,
failure and Ctrl-C.
"""

from __future__ import annotations

import json
import math
import re
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from ground.ground_log import GroundLog
from ground.station import GroundError, GroundStation
from robot.config import VmnavConfig
from robot.control_law import settling_distance_m
from shared.clock import WallClock
from shared.config import LogConfig
from shared.errors import InputError, TransportError
from shared.logs import topics
from shared.logs.reader import read_messages
from shared.mavlink.mission.goal import Goal
from shared.memory import read_memory
from shared.pose import Pose2
from sim.config import SimConfig
from sim.teach_driver import TeachDriver
from sim.world import load_world
from tools.figures.demo_report import SETTLED_M, track_errors, track_metrics
from tools.harness.demo import START_KEY_INDEX, START_OFFSET_DEG, START_OFFSET_M
from tools.harness.station_hands import StationHands
from tools.harness.teach import DRIVER_STREAM, find_route
from tools.harness.vmnav_process import VmnavProcess

#: The operator's command period, s (MANUAL_CONTROL at 10 Hz).
OPERATOR_PERIOD_S = 0.1
#: How long a process may take to print where it listens, s.
START_TIMEOUT_S = 60.0
#: SIGTERM, then SIGKILL after this long, s.
STOP_GRACE_S = 10.0


@dataclass(frozen=True, eq=False)
class Drive:
    """A true trajectory: times (s, simulation) and (N, 3) poses (x_m, y_m, yaw_rad)."""

    t_s: np.ndarray
    poses_w: np.ndarray


class SimControl:
    """The simulator's control endpoint (``sim.control_server``) over HTTP."""

    def __init__(self, url: str) -> None:
        self.url = url

    def truth(self) -> tuple[int, Pose2]:
        """(simulation time ns, true pose)."""
        data = self._call("GET", "/truth", None)
        x, y, yaw = data["pose_w"]
        return int(data["t_ns"]), Pose2(x, y, yaw)

    def place(self, pose_w: Pose2) -> None:
        """Carry the robot to ``pose_w``.

        Raises:
            InputError: the simulator refused (an obstacle there).
        """
        self._call("POST", "/place", {"pose_w": list(pose_w)})

    def _call(self, method: str, path: str, body: dict[str, Any] | None) -> dict[str, Any]:
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.url + path, data=data, method=method,
                                         headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(request, timeout=10) as reply:
                return json.loads(reply.read())
        except urllib.error.HTTPError as e:
            raise InputError(self.url + path, json.loads(e.read()).get("error", str(e))) from None
        except (urllib.error.URLError, OSError) as e:
            raise TransportError(self.url + path, str(e)) from None


class Processes:
    """``vmnav`` child processes (:class:`~tools.harness.vmnav_process.VmnavProcess`) with their
    output in files; all stopped on :meth:`stop`."""

    def __init__(self, folder: Path) -> None:
        self._folder = folder
        self._children: list[tuple[str, VmnavProcess]] = []

    def start(self, name: str, argv: list[str]) -> Path:
        """Start ``vmnav ARGV...`` as ``name``; returns its output file."""
        child = VmnavProcess(argv, self._folder / f"{name}.out", STOP_GRACE_S)
        self._children.append((name, child))
        return child.out

    def wait_for(self, name: str, pattern: str) -> re.Match[str]:
        """The first match of ``pattern`` in ``name``'s output.

        Raises:
            TransportError: the process ended first, or nothing matched in time.
        """
        child = dict(self._children)[name]
        limit = time.monotonic() + START_TIMEOUT_S
        while time.monotonic() < limit:
            found = re.search(pattern, child.output())
            if found:
                return found
            if child.process.poll() is not None:
                break
            time.sleep(0.1)
        raise TransportError(f"vmnav {name}", f"did not start: {child.last_line()} "
                                              f"(see {child.out})")

    def stop(self) -> dict[str, int]:
        """SIGTERM every child (last started first), SIGKILL those still running after
        the grace period; their exit codes."""
        return {name: child.stop() for name, child in reversed(self._children)}


def run_hil(out: Path, config: VmnavConfig, sim_config: SimConfig, robot_config_file: Path,
            route_name: str | None = None,
            watch: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run the three-process demo (module docstring); returns the report.

    Args:
        out: the output folder (memory, state, logs, process outputs, report).
        config: the demo's configs (the follow law; teleoperation scaling).
        sim_config: the world and seed.
        robot_config_file: the config file ``vmnav robot`` runs with (the follow law, the
            camera mount), and ``vmnav sim serve`` too (the camera mount).
        route_name: the route to teach and repeat; None: the world's first.
        watch: serve the web app while it runs and call this with its URL; None: no web
            app.

    Raises:
        TransportError: a process did not start or a link failed.
        GroundError: the robot refused or did not answer the ground station.
        InputError: the world has no route, or the robot could not be placed.
    """
    world = load_world(sim_config.world)
    if not world.routes:
        raise InputError(f"world {world.name!r}", "has no routes to teach")
    route = world.routes[0] if route_name is None else find_route(world, route_name)
    for name in ("memory", "state"):
        if (out / name).exists():
            raise InputError(out / name, "exists: --hil teaches anew; remove it or choose "
                                         "another --out")
    logs = out / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    clock = WallClock()
    started = time.perf_counter()
    with ExitStack() as stack:
        processes = Processes(out)
        stack.callback(processes.stop)
        processes.start("sim", ["sim", "serve", "--config", str(robot_config_file), "--world",
                                sim_config.world, "--seed", str(sim_config.seed), "--aria",
                                "tcp:0", "--video", "http:0", "--control", "http:0"])
        aria = processes.wait_for("sim", r"ARIA on tcp (\S+)").group(1)
        camera = processes.wait_for("sim", r"camera on (\S+/stream\.mjpg)").group(1)
        sim = SimControl(processes.wait_for("sim", r"control on (\S+) ").group(1))
        sim.place(route.start_pose())
        station = stack.enter_context(GroundStation.open("udpin:127.0.0.1:0", clock))
        ground_log = GroundLog(LogConfig(output_dir=str(logs)), clock,
                               time.time_ns() - clock.now_ns())
        stack.callback(ground_log.close)
        station.packet_taps.append(ground_log.record)
        hands = StationHands(station, clock, None if watch is None else
                             _serve_web(stack, station, clock, logs, watch))
        processes.start("robot", [
            "robot", "--aria", f"socket://{aria}", "--camera", camera, "--mavlink",
            f"udpout:127.0.0.1:{station.link.local_port}", "--memory", str(out / "memory"),
            "--state", str(out / "state"), "--log", str(logs), "--config",
            str(robot_config_file), *(["--video", "http:127.0.0.1:0"] if watch else [])])
        hands.do(lambda s: s.wait_vehicle(START_TIMEOUT_S))
        taught = teach(hands, sim, route.waypoints, config, sim_config, route.name)
        memory = read_memory(out / "memory")
        path = next(p for p in memory.paths.values() if p.name == route.name)
        start_key = memory.keyframes[path.keyframe_ids[min(START_KEY_INDEX,
                                                          len(path.keyframe_ids) - 1)]]
        start_pose = offset_start(taught, start_key.distance_m)
        sim.place(start_pose)
        goal = path.keyframe_ids[-1]
        repeat, upload_ms = follow(hands, sim, goal, config)
        wall_s = time.perf_counter() - started
        notices = hands.do(lambda s: tuple(s.vehicle.notices) if s.vehicle is not None else ())
        outcome = hands.do(lambda s: s.mission_outcome)
    exit_codes = processes.stop()
    servo = servo_figures(sorted(logs.glob("robot-*.mcap")))
    settle_m = settling_distance_m(config.control.pole_1_m, START_OFFSET_M, SETTLED_M)
    errors = track_errors(repeat.poses_w, taught.poses_w) if len(repeat.t_s) >= 2 else None
    final, end = repeat.poses_w[-1], taught.poses_w[-1]
    return {
        "mode": "hil: vmnav sim serve + vmnav robot + ground station, separate processes",
        "route": route.name,
        "reached_goal": outcome is True,
        "goal_key_image": goal,
        "key_images_taught": len(path.keyframe_ids),
        "start_pose": [round(v, 4) for v in start_pose],
        "final_position_error_m": round(math.hypot(final[0] - end[0], final[1] - end[1]), 4),
        "settling_distance_m": round(settle_m, 4),
        **track_metrics(errors, settle_m),
        "teach_sim_time_s": round(float(taught.t_s[-1] - taught.t_s[0]), 2),
        "repeat_sim_time_s": round(float(repeat.t_s[-1] - repeat.t_s[0]), 2),
        "wall_time_s": round(wall_s, 2),
        "mission_upload_ms": round(upload_ms, 1),
        **servo,
        "notices": list(notices),
        "exit_codes": exit_codes,
    }


def _serve_web(stack: ExitStack, station: GroundStation, clock: WallClock, logs: Path,
               watch: Callable[[str], None]) -> Any:
    """Serve the web app on a free loopback port until ``stack`` closes (before the station
    does); announce its URL; its station loop, started."""
    from ground.web.server import WebConfig, WebServer

    server = WebServer(station, clock, WebConfig(port=0, log_dir=logs))
    serving = threading.Thread(target=server.run, name="hil-web", daemon=True)
    serving.start()

    def stop() -> None:
        server.stop()
        serving.join(START_TIMEOUT_S)

    stack.callback(stop)
    limit = time.monotonic() + START_TIMEOUT_S
    while not server.started:
        if not serving.is_alive() or time.monotonic() > limit:
            raise TransportError(server.url, "the web app did not start")
        time.sleep(0.05)
    watch(server.url)
    return server.station_loop


def teach(hands: StationHands, sim: SimControl, waypoints: Any, config: VmnavConfig,
          sim_config: SimConfig, name: str) -> Drive:
    """Teach ``name`` by teleoperation (module step 1, the operator ``sim_config``'s teach
    driver, seeded from its seed); the true drive.

    Raises:
        GroundError: the robot refused teaching, or did not store the path.
    """
    driver = TeachDriver(waypoints, sim_config.teach_driver,  # the lock-step teacher's draws
                         np.random.default_rng([sim_config.seed, DRIVER_STREAM]))
    teleop = config.teleop
    hands.do(lambda s: s.teach_start(name))
    times, poses = [], []
    limit = time.monotonic() + 3 * driver.length_m / sim_config.teach_driver.speed_m_s + 30
    while not driver.done:
        if time.monotonic() > limit:
            raise GroundError(f"teach {name!r}: the operator did not reach the route's end")
        t_ns, pose = sim.truth()
        times.append(t_ns / 1e9)
        poses.append(pose)
        command = driver.command(pose)
        x = float(np.clip(command.v_m_s / teleop.max_speed_m_s, -1, 1))
        r = float(np.clip(-command.omega_rad_s / teleop.max_omega_rad_s, -1, 1))
        hands.do(lambda s, x=x, r=r: s.send_manual_control(x, r))
        hands.wait(round(OPERATOR_PERIOD_S * 1e9))
    hands.do(lambda s: s.send_manual_control(0.0, 0.0))
    hands.wait(1_000_000_000)  # let the robot stop on its last frames
    t_ns, pose = sim.truth()
    times.append(t_ns / 1e9)
    poses.append(pose)
    hands.do(lambda s: s.teach_stop())  # waits while the robot stores the path; raises if not
    return Drive(np.array(times), np.array(poses))


def offset_start(taught: Drive, distance_m: float) -> Pose2:
    """The lock-step demo's start: the taught drive's pose ``distance_m`` along it, moved
    ``START_OFFSET_M`` to its left and turned ``START_OFFSET_DEG``."""
    steps = np.hypot(*np.diff(taught.poses_w[:, :2], axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(steps)])
    i = int(np.searchsorted(along, distance_m).clip(0, len(along) - 1))
    x, y, yaw = taught.poses_w[i]
    return Pose2(float(x - START_OFFSET_M * math.sin(yaw)),
                 float(y + START_OFFSET_M * math.cos(yaw)),
                 float(yaw + math.radians(START_OFFSET_DEG)))


def follow(hands: StationHands, sim: SimControl, goal: int,
           config: VmnavConfig) -> tuple[Drive, float]:
    """Dispatch ``goal`` and record the true trajectory until the ground sees the outcome
    (module step 2); the drive and the mission upload's time to MISSION_ACK, ms."""
    uploaded = time.perf_counter()
    hands.do(lambda s: s.upload_goals([Goal(goal)]))
    upload_ms = (time.perf_counter() - uploaded) * 1e3
    hands.do(lambda s: s.start_mission())

    def ended(s: GroundStation) -> bool:
        return s.mission_outcome is not None

    times, poses = [], []
    limit = time.monotonic() + 300.0
    while not hands.do(ended) and time.monotonic() < limit:
        t_ns, pose = sim.truth()
        times.append(t_ns / 1e9)
        poses.append(pose)
        hands.wait(round(OPERATOR_PERIOD_S * 1e9), ended)
    t_ns, pose = sim.truth()
    times.append(t_ns / 1e9)
    poses.append(pose)
    return Drive(np.array(times), np.array(poses)), upload_ms


def servo_figures(robot_logs: list[Path]) -> dict[str, Any]:
    """What the robot's field log says of the repeat (its ``/servo/state``): key images
    reached (switches), mean matches and the servo loop's processing time (median, p95,
    ms) while following, LOST events; the lock-step report's figures that only the
    robot process knows."""
    switches = lost = 0
    matches: list[int] = []
    loop_ms: list[float] = []
    for path in robot_logs:
        for message in read_messages(path, [topics.SERVO_STATE]):
            state = message.data
            switches += state["switch_reason"] is not None
            lost += bool(state["lost"])
            if state["mission_state"] == "following":
                matches.append(state["matched_points"])
                loop_ms.append(state["compute_ms"])
    return {"key_images_reached": switches, "lost_events": lost,
            "mean_matches": round(float(np.mean(matches)), 1) if matches else None,
            "loop_ms_p50": round(float(np.percentile(loop_ms, 50)), 2) if loop_ms else None,
            "loop_ms_p95": round(float(np.percentile(loop_ms, 95)), 2) if loop_ms else None}


def robot_config_text(config: VmnavConfig) -> str:
    """The TOML ``vmnav robot`` and ``vmnav sim serve`` run with in the HIL demo: the
    demo's follow law, and the camera mount (where the robot thinks its camera is and the
    simulator puts it)."""
    mount = config.camera.mount
    return (f"[control]\nlaw = \"{config.control.law}\"\n"
            f"max_omega_rad_s = {config.control.max_omega_rad_s!r}\n"
            "[camera.mount]\n"
            + "".join(f"{f.name} = {getattr(mount, f.name)!r}\n" for f in fields(mount)))
