"""Issue 8's faults on the hardware-in-the-loop rig: one function per case, which the tests
(``tests/tools/bench/test_faults.py``) and ``vmnav bench faults`` both run.

Every case takes the taught route (:class:`tools.harness.hil_rig.Taught`, taught once) and a
fresh folder, builds its own rig (:func:`tools.harness.hil_rig.open_hil`: the simulator's
objects in this process, ``vmnav robot`` as a subprocess, a ground station here),
injects its fault through the simulator's hooks or from outside, and raises
:class:`~tools.harness.hil_rig.FaultCaseError` with one line when the robot behaves otherwise
than the README's "Faults" section says. Missions go to key images of ``east_a``
from its start, where the world puts the robot.

The garbage cases are in :mod:`tools.harness.fault_garbage`; :mod:`tools.bench.faults` lists them
all and repeats them.
"""

from __future__ import annotations

import base64
import math
import subprocess
import sys
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from robot.config import BASE_LOST_ACTIONS, TeleopConfig
from shared.clock import NS_PER_S
from shared.config import GCS_LOST_ACTIONS, AriaLinkConfig, MavlinkConfig
from shared.logs import topics
from shared.logs.reader import log_info, read_messages
from shared.mavlink.modes import Mode
from tools.harness.hil_rig import STILL_M_S, Hil, Taught, expect, open_hil

#: Driven before a fault is injected, m (the robot is following by then).
DRIVEN_BEFORE_FAULT_M = 0.4
#: How close to the goal key image's place the robot must stop, m.
GOAL_TOLERANCE_M = 0.15
#: Braking from the route's 0.2 m/s (0.6 m/s^2: 0.33 s) plus a margin for a loaded machine, ns.
BRAKE_NS = 500_000_000
#: After the robot's frame timeout, its loop notices (up to a frame period), stops the
#: base and the base brakes: the body stands still this long after, ns.
HOLD_AFTER_NS = BRAKE_NS + 300_000_000
#: The ARIA cut, s: longer than the driver's link timeout, so it gives the link up and
#: reconnects (a shorter cut resumes the same session once the bytes flow again).
CUT_S = AriaLinkConfig().link_timeout_ns / NS_PER_S + 1.0
#: The camera stall and the ground station's silence, s (issue 8).
STALL_S = 2.0
SILENCE_S = 10.0
#: How late a loaded robot may notice a camera stall, past its frame timeout, s.
NOTICE_LATE_S = 0.5
#: Time for a mission to reach its goal after the fault, s.
REACH_S = 45.0
#: A killed robot's log loses at most this much (DESIGN.md sec. 4 "Logs"), ns.
LOG_LOSS_NS = NS_PER_S
#: The parameter the SIGKILL case sets from the ground, and its value.
KILL_PARAM, KILL_PARAM_VALUE = "CTL_SPEED", 0.25


@dataclass(frozen=True)
class Silence:
    """A silence of the ground station, in simulation time.

    Attributes:
        began_ns: the simulation's time when the silence began, ns.
        since: the number of the robot's notices before it (``since`` of
            :meth:`~tools.harness.hil_rig.Hil.notice`).
        marked_ns: the simulation's time when the wall clock had run ``mark_ns`` of the
            silence, ns: where a timeout the robot times on its wall clock fell in the
            simulation, which lags the wall clock on a loaded machine.
    """

    began_ns: int
    since: int
    marked_ns: int


def go_silent(hil: Hil, seconds: float, mark_ns: int) -> Silence:
    """The ground station sends nothing (and reads nothing) for ``seconds``, noting the
    simulation's time ``mark_ns`` into it on the wall clock. Then waits until the robot says
    it heard the station again, and until the simulation has run ``seconds`` past the
    silence's start."""
    began_ns, since = hil.sim.now_ns, len(hil.notices())
    clock = hil.station.clock
    start_ns = clock.now_ns()
    clock.sleep_until_ns(start_ns + mark_ns)
    marked_ns = hil.sim.now_ns
    clock.sleep_until_ns(start_ns + round(seconds * NS_PER_S))
    hil.run_until(lambda: hil.notice("GCS heartbeat regained", since) is not None, 5.0,
                  "the robot's 'GCS heartbeat regained'")
    hil.wait_sim(began_ns + round(seconds * NS_PER_S))
    return Silence(began_ns, since, marked_ns)


# -- the cases ----------------------------------------------------------------------------


def cut_aria_link(hil: Hil) -> int:
    """Cut the ARIA cable for :data:`CUT_S` and wait until the robot says its base reports
    again. Checks that the Pioneer's watchdog stopped the base (the robot's own stop cannot
    reach it through a cut cable), and that the robot said the base went quiet.

    Returns:
        The number of the robot's notices before the cut (``since`` of
        :meth:`~tools.hil_rig.Hil.notice`).
    """
    cut_ns, cut_length_ns, since = hil.sim.now_ns, round(CUT_S * NS_PER_S), len(hil.notices())
    hil.sim.server.cut(cut_length_ns)
    hil.wait_sim(cut_ns + cut_length_ns)
    watchdog_ns = hil.sim.emulator.config.link.watchdog_timeout_ns
    moving = hil.sim.truth.still(cut_ns + watchdog_ns + BRAKE_NS, cut_ns + cut_length_ns)
    expect(moving is None, f"the base did not stop within the watchdog time: {moving}")
    expect(hil.sim.emulator.stats.watchdog_trips >= 1, "the emulator's watchdog never tripped")
    expect(hil.notice("base not reporting: stopped", since) is not None,
           f"no 'base not reporting' notice: {hil.notices()}")
    hil.run_until(lambda: hil.notice("base reporting again", since) is not None, 20.0,
                  "the robot's 'base reporting again'")
    connects = hil.robot.output().count("pioneer: connected to")
    expect(connects >= 2, f"the driver connected {connects} time(s): no reconnection")
    return since


def aria_link_cut(taught: Taught, folder: Path) -> None:
    """The ARIA link is cut mid-route for :data:`CUT_S` (``FS_BASE_ACTION`` continue, the
    default): the robot stops when the SIPs stop, the driver gives the link up and
    reconnects, the mission resumes to its goal."""
    goal = taught.keyframe_ids[6]
    with open_hil(taught, folder) as hil:
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        since = cut_aria_link(hil)
        expect(hil.notice("base not reporting: stopped, mission paused", since) is not None,
               f"no 'mission paused' notice: {hil.notices()}")
        expect(hil.notice(r"base reporting again after [\d.]+ s, mission resumes", since)
               is not None, f"no 'mission resumes' notice: {hil.notices()}")
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def aria_link_cut_hold(taught: Taught, folder: Path) -> None:
    """As :func:`aria_link_cut` with ``FS_BASE_ACTION`` set to "hold" from the ground: the
    mission ends in HOLD, the robot stays put when the base is back, MISSION_START resumes."""
    goal = taught.keyframe_ids[6]
    with open_hil(taught, folder) as hil:
        hil.station.set_param("FS_BASE_ACTION", float(BASE_LOST_ACTIONS.index("hold")))
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        since = cut_aria_link(hil)
        back_ns = hil.sim.now_ns
        expect(hil.notice("base not reporting: stopped, mission held", since) is not None,
               f"no 'mission held' notice: {hil.notices()}")
        expect(hil.vehicle.mode is Mode.HOLD, f"mode {hil.vehicle.mode_name} after the cut")
        expect(hil.station.mission_outcome is False,
               f"mission outcome {hil.station.mission_outcome} after the hold, expected False")
        hil.wait_sim(back_ns + round(STALL_S * NS_PER_S))
        moving = hil.sim.truth.still(back_ns, back_ns + round(STALL_S * NS_PER_S))
        expect(moving is None, f"the robot moved in HOLD after the base came back: {moving}")
        hil.station.start_mission()
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def camera_stall(taught: Taught, folder: Path) -> None:
    """The camera stream stalls for :data:`STALL_S` mid-route: the robot stops within the
    frame timeout, says so, and carries on to its goal when frames return."""
    goal = taught.keyframe_ids[5]
    with open_hil(taught, folder) as hil:
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        stall_ns, stall_length_ns = hil.sim.now_ns, round(STALL_S * NS_PER_S)
        since, stalled_wall_ns = len(hil.notices()), hil.station.clock.now_ns()
        hil.sim.camera.stall(stall_length_ns)
        hil.run_until(lambda: hil.notice("camera back", since) is not None, STALL_S + 10.0,
                      "the robot's 'camera back'")
        # The robot times the stall on its (wall) clock from when it noticed it, so it saw
        # no longer than this, and no less than this minus its frame timeout and a margin
        # for noticing late; the stall is in frame time, which lags on a loaded machine (or
        # skips ahead to catch up, ending the stall sooner on the wall clock).
        seen_s = (hil.station.clock.now_ns() - stalled_wall_ns) / NS_PER_S
        least_s = seen_s - TeleopConfig().frame_timeout_ns / NS_PER_S - NOTICE_LATE_S
        moving = hil.sim.truth.still(stall_ns + TeleopConfig().frame_timeout_ns + HOLD_AFTER_NS,
                                     stall_ns + stall_length_ns)
        expect(moving is None, f"the base did not hold while the camera stalled: {moving}")
        expect(hil.notice("camera stalled: stopped", since) is not None,
               f"no 'camera stalled' notice: {hil.notices()}")
        back = hil.notice(r"camera back after ([\d.]+) s", since)
        lasted = math.nan if back is None else float(back.group(1))
        expect(least_s <= lasted <= seen_s + 0.1,  # 0.1: the notice's rounding
               f"the robot saw a {lasted} s stall, the camera stalled {STALL_S} s of frame "
               f"time, {seen_s:.2f} s on the wall clock until the robot said it was back")
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def gcs_silent_hold(taught: Taught, folder: Path) -> None:
    """The ground station goes silent for :data:`SILENCE_S` during an AUTO mission with the
    default failsafe ("hold"): the robot drives on until the GCS timeout, then holds in
    HOLD (the mission run ends short) and reports both; MISSION_START resumes it."""
    goal = taught.keyframe_ids[-1]
    with open_hil(taught, folder) as hil:
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        silence = go_silent(hil, SILENCE_S, MavlinkConfig().gcs_timeout_ns)
        # Nominally 0.4 m at 0.2 m/s. The robot times the GCS timeout on its wall clock and
        # the simulation lags the wall on a loaded machine, so fewer simulated metres fit
        # before the hold: what is checked is that it drove on (a robot that stopped at
        # the silence's start coasts a few cm), not how far.
        driven = hil.sim.truth.travelled_m(silence.began_ns, silence.marked_ns - NS_PER_S)
        expect(driven > 0.15, f"the robot drove only {driven:.2f} m before the GCS timeout")
        moving = hil.sim.truth.still(silence.marked_ns + BRAKE_NS,
                                     silence.began_ns + round(SILENCE_S * NS_PER_S))
        expect(moving is None, f"the robot did not hold after the GCS timeout: {moving}")
        expect(hil.notice(r"GCS heartbeat lost for [\d.]+ s in AUTO: hold", silence.since)
               is not None, f"no failsafe notice: {hil.notices()}")
        expect(hil.vehicle.mode is Mode.HOLD, f"mode {hil.vehicle.mode_name} after the failsafe")
        expect(hil.station.mission_outcome is False,
               f"mission outcome {hil.station.mission_outcome} after the hold, expected False")
        hil.station.start_mission()
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def gcs_silent_continue(taught: Taught, folder: Path) -> None:
    """As :func:`gcs_silent_hold` with ``FS_GCS_ACTION`` set to "continue" from the ground:
    the robot reports the loss and carries on to its goal."""
    goal = taught.keyframe_ids[-1]
    with open_hil(taught, folder) as hil:
        hil.station.set_param("FS_GCS_ACTION", float(GCS_LOST_ACTIONS.index("continue")))
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        silence = go_silent(hil, SILENCE_S, MavlinkConfig().gcs_timeout_ns)
        driven = hil.sim.truth.travelled_m(silence.marked_ns + BRAKE_NS,
                                           silence.began_ns + round(SILENCE_S * NS_PER_S))
        # Nominally 0.9 m; a robot that held instead would coast a few cm after braking.
        expect(driven > 0.2, f"the robot drove only {driven:.2f} m after the GCS timeout")
        expect(hil.notice(r"GCS heartbeat lost for [\d.]+ s in AUTO: continue", silence.since)
               is not None, f"no failsafe notice: {hil.notices()}")
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def gcs_silent_manual(taught: Taught, folder: Path) -> None:
    """The ground station goes silent for :data:`SILENCE_S` while driving the robot in
    MANUAL: no MANUAL_CONTROL stops it at once (the dead-man), the failsafe reports
    "stop", and it stays stopped in MANUAL."""
    with open_hil(taught, folder) as hil:
        hil.station.set_mode(Mode.MANUAL)

        def drive() -> bool:
            hil.station.send_manual_control(0.5, 0.0)
            return hil.sim.truth.moved_m() >= DRIVEN_BEFORE_FAULT_M / 2

        hil.run_until(drive, 10.0, "driving by MANUAL_CONTROL")
        silence = go_silent(hil, SILENCE_S, TeleopConfig().deadman_ns)
        moving = hil.sim.truth.still(silence.marked_ns + BRAKE_NS,
                                     silence.began_ns + round(SILENCE_S * NS_PER_S))
        expect(moving is None, f"the robot did not stop without the ground: {moving}")
        expect(hil.notice(r"GCS heartbeat lost for [\d.]+ s in MANUAL: stop", silence.since)
               is not None, f"no failsafe notice: {hil.notices()}")
        expect(hil.vehicle.mode is Mode.MANUAL,
               f"mode {hil.vehicle.mode_name} after the failsafe")


def robot_sigkill(taught: Taught, folder: Path) -> None:
    """``vmnav robot`` is killed with SIGKILL mid-mission, after a parameter was set from the
    ground: ``vmnav log recover`` rewrites its field log with every message older than
    :data:`LOG_LOSS_NS` before the kill (witness: the MAVLink packets the ground received
    from it), and a restarted robot loads the memory and the parameters unchanged."""
    goal = taught.keyframe_ids[-1]
    with open_hil(taught, folder) as hil:
        speed = hil.station.set_param(KILL_PARAM, KILL_PARAM_VALUE)
        kept = stored_files(folder)
        received: list[tuple[int, bytes]] = []  # (arrival ns, packet) of the robot's packets

        def tap(way: str, packet: bytes, msg: object, t_ns: int) -> None:
            if way == "in":
                received.append((t_ns, packet))

        hil.station.packet_taps.append(tap)
        hil.start_goal(goal, 2 * DRIVEN_BEFORE_FAULT_M)
        killed_ns = hil.station.clock.now_ns()
        hil.robot.kill()
        log, recovered = folder / "logs" / "robot-0001.mcap", folder / "robot-0001.recovered.mcap"
        done = subprocess.run([sys.executable, "-m", "tools.cli", "log", "recover", str(log),
                               "-o", str(recovered)], capture_output=True, text=True, timeout=60)
        expect(done.returncode == 0 and log_info(recovered).complete,
               f"vmnav log recover {log}: {done.stderr.strip()}")
        logged = read_messages(recovered, [topics.MAVLINK_RAW])
        out = Counter(base64.b64decode(m.data["frame"]) for m in logged
                      if m.data["direction"] == "out")
        sent = Counter(packet for t_ns, packet in received if t_ns < killed_ns - LOG_LOSS_NS)
        missing = sum((sent - out).values())
        expect(sent.total() > 0 and missing == 0,
               f"{missing} of the {sent.total()} MAVLink packets the robot sent more than "
               f"{LOG_LOSS_NS / NS_PER_S:g} s before the kill are not in the recovered log")
        hil.restart_robot("robot-2.out")
        now = stored_files(folder)
        changed = [name for name in kept.keys() | now.keys() if kept.get(name) != now.get(name)]
        expect(not changed, f"changed by the kill and the restart: {sorted(changed)}")
        loaded = f"memory {folder / 'memory'}: 1 paths, {len(taught.keyframe_ids)} key images"
        expect(loaded in hil.robot.output(), f"the restarted robot did not load the memory: "
                                             f"{hil.robot.last_line()}")
        value = hil.station.get_param(KILL_PARAM)
        expect(value == speed, f"{KILL_PARAM} = {value} after the restart, set to {speed}")


def emergency_stop_once(hil: Hil) -> tuple[float, float]:
    """``vmnav ground stop`` while the robot drives: wait until the body stands still.

    Returns:
        From the ground station's send to the emulated Pioneer's E_STOP (its motors off),
        and to the body at rest, s of simulated time (which runs at the wall clock's pace).

    Raises:
        FaultCaseError: the E_STOP never came, or the body did not come to rest in 5 s.
    """
    sim = hil.sim
    stopped_ns: list[int] = []

    def watch(now_ns: int, dt_ns: int) -> None:
        if not stopped_ns and not sim.emulator.motors_enabled:
            stopped_ns.append(now_ns)

    sent_ns = sim.now_ns
    sim.sim.add_step_hook(watch)
    hil.station.emergency_stop()
    hil.wait_sim(sent_ns + 5 * NS_PER_S)
    expect(bool(stopped_ns), "the emulated Pioneer never got E_STOP")
    rest = [t for t, speed in sim.truth.speeds(sent_ns, sent_ns + 5 * NS_PER_S)
            if speed >= STILL_M_S]
    at_rest_ns = (rest[-1] if rest else sent_ns) - sent_ns
    expect(at_rest_ns < 5 * NS_PER_S - BRAKE_NS, "the body was still moving 4.5 s after the stop")
    return (stopped_ns[0] - sent_ns) / NS_PER_S, at_rest_ns / NS_PER_S


def emergency_stop(taught: Taught, folder: Path) -> None:
    """``vmnav ground stop`` mid-route (a forced disarm): the Pioneer gets E_STOP and the body
    comes to rest within :data:`BRAKE_NS`; the mission ends as ``e_stop``; the robot holds
    while disarmed; armed again and restarted, it reaches its goal."""
    goal = taught.keyframe_ids[6]
    with open_hil(taught, folder) as hil:
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        since = len(hil.notices())
        _, rest_s = emergency_stop_once(hil)
        expect(rest_s <= BRAKE_NS / NS_PER_S + 0.5,
               f"at rest {rest_s:.2f} s after the emergency stop")
        hil.run_until(lambda: hil.notice("e_stop: emergency stop", since) is not None, 5.0,
                      "the robot's 'e_stop: emergency stop'")
        held_ns = hil.sim.now_ns
        hil.wait_sim(held_ns + round(STALL_S * NS_PER_S))
        moving = hil.sim.truth.still(held_ns, held_ns + round(STALL_S * NS_PER_S))
        expect(moving is None, f"the robot moved while emergency-stopped: {moving}")
        hil.station.arm()
        hil.station.start_mission()
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)


def stored_files(folder: Path) -> dict[str, bytes]:
    """Every file of ``folder/memory`` and ``folder/state``: relative name -> bytes."""
    return {str(path.relative_to(folder)): path.read_bytes()
            for part in ("memory", "state") for path in sorted((folder / part).rglob("*"))
            if path.is_file()}
