"""``vmnav bench safety``: issue 17's numbers, from the simulator's truth.

Four parts, each a key of the JSON:

* ``scenarios``: every scenario of :mod:`tools.harness.safety_scenarios` once, with the
  robot's default safety settings (a person standing 90 s against the 60 s wait);
* ``people``: per world and seed, the demo's repeat (:func:`tools.harness.demo.repeat_in_sim`)
  with ``--people`` people walking who do not avoid the robot, and the same seed
  without people: goals reached, lateral RMS with and without, contacts the robot
  caused (moving towards a person) and people walking into the robot (standing, or
  driving past them; each contact: when, where in the robot frame, how fast the robot
  moved towards them),
  and the longest distance driven without a verified localization (true metres since
  the last vision estimate the filter took, or the last localization);
* ``e_stop``: ``--estops`` emergency stops on the hardware-in-the-loop rig
  (``vmnav robot`` as a process, the emulated Pioneer on TCP, the ground station on UDP):
  from the ground's send to the Pioneer's E_STOP, and to the body at rest, p50/p95/max;
* ``governor``: the safety layer's cost per servo frame (two
  :meth:`~robot.safety.SafetyGovernor.assess` calls, the readings arriving as a P3 sends
  them), ms.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import asdict, replace
from pathlib import Path
from statistics import median
from typing import Any

#: What ``vmnav bench all`` holds the figures to (issue 17).
TARGETS: dict[str, tuple[str, float | str]] = {
    "scenarios_failed": ("==", 0),
    "people_contacts_moving": ("==", 0),
    "people_reached_short": ("<=", 1),
    "people_lateral_rms_delta_m_max": ("<=", 0.01),
    "blind_m_over_bound": ("<=", 0.0),
    "e_stop_latency_ms_p95": ("<", 100.0),
    "e_stop_at_rest_s_max": ("<=", 0.5),
    "governor_frame_ms_p95": ("<", 0.5),
}
#: Braking allowed past the lost distance before the body stands: one frame at the route's
#: 0.2 m/s and the Pioneer's deceleration to rest, m.
BLIND_BRAKING_M = 0.05


def scenarios_part(out: Path) -> list[dict[str, Any]]:
    """Each scenario once on ``east_a`` taught into ``out/taught`` (seed 1)."""
    from robot.config import VmnavConfig
    from tools.harness.safety_scenarios import run_scenario, scenarios
    from tools.harness.short_routes import teach_east_a

    config = VmnavConfig()
    folder = out / "taught"
    folder.mkdir(parents=True, exist_ok=True)
    world_file, _ = teach_east_a(folder, config)
    rows = []
    for scenario in scenarios().values():
        print(f"vmnav bench safety: scenario {scenario.name}", file=sys.stderr, flush=True)
        result = run_scenario(scenario, world_file, folder / "memory", config)
        rows.append({k: v for k, v in asdict(result).items() if k != "transitions"}
                    | {"expect": scenario.expect})
    return rows


def people_part(worlds: list[str], seeds: range, people: int, out: Path,
                args: argparse.Namespace) -> dict[str, Any]:
    """Per world: the seeds' repeats with and without people (module docstring)."""
    from robot.config import load_config
    from sim.config import PeopleConfig
    from sim.scene_change import SceneChange
    from tools.figures.demo_report import build_report
    from tools.harness.demo import (
        default_goal,
        repeat_in_sim,
        taught_memory,
    )
    from tools.harness.safety_truth import judge, safety_figures
    from tools.harness.sim_args import sim_config_from_args

    config = load_config(args.config)
    result: dict[str, Any] = {}
    for world in worlds:
        base_sim, camera = sim_config_from_args(argparse.Namespace(
            config=args.config, world=world, seed=None, calibration=args.calibration, people=None))
        rows = []
        for seed in seeds:
            seeded = replace(base_sim, seed=seed)
            folder = out / world / f"seed{seed}"
            taught = taught_memory(folder, None, config, seeded, camera)
            goal = default_goal(taught)
            row: dict[str, Any] = {"seed": seed}
            for label, count in (("with", people), ("without", 0)):
                print(f"vmnav bench safety: {world} seed {seed} {label} people",
                      file=sys.stderr, flush=True)
                sim_config = replace(seeded, people=PeopleConfig(count=count, avoid_robot=False))
                hook, truths = judge(config)
                started = time.perf_counter()
                run = repeat_in_sim(taught, goal, config, sim_config, SceneChange(),
                                    folder / label, on_sim=hook)
                truths[0].finish()
                report = build_report(run, taught, config.control, time.perf_counter() - started)
                row[label] = {
                    "reached": run.result.reached_goal,
                    "end": f"{run.result.reason}: {run.result.detail}",
                    "lateral_rms_m": report["lateral_rms_m"],
                    **safety_figures(truths[0], run),
                    "contacts": [asdict(c) for c in truths[0].contacts],
                }
            rows.append(row)
            print(f"vmnav bench safety: {world} seed {seed}: {json.dumps(row)}", file=sys.stderr,
                  flush=True)
        with_rows = [r["with"] for r in rows]
        # over the seeds both runs followed to the goal: a run cut short has its start's RMS
        deltas = [r["with"]["lateral_rms_m"] - r["without"]["lateral_rms_m"] for r in rows
                  if r["with"]["reached"] and r["without"]["reached"]
                  and r["with"]["lateral_rms_m"] is not None
                  and r["without"]["lateral_rms_m"] is not None]
        result[world] = {
            "seeds": rows,
            "reached_with_people": sum(r["reached"] for r in with_rows),
            "reached_without_people": sum(r["without"]["reached"] for r in rows),
            "contacts_moving": sum(r["contacts_moving"] for r in with_rows),
            "contacts_still": sum(r["contacts_still"] for r in with_rows),
            "lateral_rms_delta_m_median": round(median(deltas), 4) if deltas else None,
            "lateral_rms_delta_m_max": round(max(deltas), 4) if deltas else None,
            "blind_m_max": max(max(r["with"]["blind_max_m"], r["without"]["blind_max_m"])
                               for r in rows),
        }
    return result


#: Emergency stops per rig: the robot drives this far between two on the 2.5 m route, m.
STOPS_PER_RIG, DRIVE_BETWEEN_M = 4, 0.4


def e_stop_part(out: Path, repeats: int) -> dict[str, Any]:
    """``repeats`` emergency stops, :data:`STOPS_PER_RIG` per rig along ``east_a``: drive
    :data:`DRIVE_BETWEEN_M`, stop, arm, restart the mission (it relocalizes), again."""
    from shared.mavlink.mission.goal import Goal
    from tools.harness.fault_cases import emergency_stop_once
    from tools.harness.hil_rig import open_hil, teach

    taught = teach(out / "taught")
    latencies, rests = [], []
    goal = taught.keyframe_ids[-1]
    for rig in range(math.ceil(repeats / STOPS_PER_RIG)):
        folder = out / f"rig{rig}"
        folder.mkdir(parents=True, exist_ok=True)
        with open_hil(taught, folder) as hil:
            hil.station.upload_goals([Goal(goal)])
            for _ in range(min(STOPS_PER_RIG, repeats - len(latencies))):
                print(f"vmnav bench safety: emergency stop {len(latencies) + 1}/{repeats}",
                      file=sys.stderr, flush=True)
                if not hil.vehicle.armed:
                    hil.station.arm()
                moved_from = hil.sim.truth.moved_m()
                hil.station.start_mission()
                hil.run_until(lambda m=moved_from: hil.sim.truth.moved_m() - m
                              >= DRIVE_BETWEEN_M, 30.0, "driving before the stop")
                latency_s, rest_s = emergency_stop_once(hil)
                latencies.append(latency_s * 1e3)
                rests.append(rest_s)
    latencies.sort()
    return {"stops": repeats, "latency_ms_p50": round(median(latencies), 1),
            "latency_ms_p95": round(latencies[min(len(latencies) - 1,
                                                  math.ceil(0.95 * len(latencies)) - 1)], 1),
            "latency_ms_max": round(latencies[-1], 1), "at_rest_s_max": round(max(rests), 3),
            "at_rest_s_median": round(median(rests), 3)}


def governor_part(frames: int = 2000) -> dict[str, float]:
    """The cost of the safety layer per frame and per assessment, the 16 sonars of a P3-AT
    reading, ms.

    As on the robot: two assessments per frame at 15 frames/s (the servo's command and the
    base's), the readings arriving as the P3 sends them (each array fires one transducer
    every 40 ms, a SIP every 100 ms carries those fired since), the robot driving at 0.2
    m/s along the middle of a corridor 2 m wide. ``frame_ms``: a frame's two assessments;
    ``ms``: one assessment; ``placing_ms``: the assessments that came with new readings
    (their echoes placed on their arcs, rule 1 of ``robot.safety``).
    """
    from robot.config import SafetyConfig
    from robot.safety import SafetyGovernor
    from shared.aria.p3at import SONAR_POSES, SONARS_PER_ARRAY
    from shared.interfaces import BaseState, RangeReading
    from shared.pose import Pose2

    governor = SafetyGovernor(SafetyConfig())
    frame_ns, sip_ns, ping_ns = 66_666_667, 100_000_000, 40_000_000
    latest: dict[int, RangeReading] = {}
    times, placing = [], []
    for k in range(2 * frames):
        t_ns = k * frame_ns // 2
        pose = Pose2(0.2 * t_ns / 1e9, 0.0, 0.0)
        sip_t = t_ns // sip_ns * sip_ns
        at_sip = Pose2(0.2 * sip_t / 1e9, 0.0, 0.0)
        # the pings each array fired (its transducers in turn) since the SIP before
        for ping in range(max(0, (sip_t - sip_ns) // ping_ns), sip_t // ping_ns):
            for array in range(2):
                number = array * SONARS_PER_ARRAY + ping % SONARS_PER_ARRAY
                _, y, heading = SONAR_POSES[number]
                s = math.sin(heading)  # to the wall on its side (y = +-1 m)
                wall_m = (math.copysign(1.0, s) - y) / s if abs(s) > 1e-3 else 5.0
                latest[number] = RangeReading(number, SONAR_POSES[number], min(wall_m, 5.0),
                                              sip_t, at_sip)
        readings = tuple(latest[i] for i in sorted(latest))
        state = BaseState(pose, 0.2, False, False, 13.0, True, ranges=readings)
        started = time.perf_counter_ns()
        governor.assess(t_ns, state, 0.2, 0.05)
        elapsed = (time.perf_counter_ns() - started) / 1e6
        times.append(elapsed)
        if t_ns - sip_t < frame_ns // 2 and readings:
            placing.append(elapsed)
    frame_times = sorted(a + b for a, b in zip(times[::2], times[1::2], strict=True))
    times.sort()
    placing.sort()
    return {"frame_ms_p50": round(frame_times[len(frame_times) // 2], 4),
            "frame_ms_p95": round(frame_times[int(0.95 * len(frame_times))], 4),
            "ms_p50": round(times[len(times) // 2], 4),
            "ms_p95": round(times[int(0.95 * len(times))], 4),
            "placing_ms_p50": round(placing[len(placing) // 2], 4)}


def summary(result: dict[str, Any]) -> dict[str, Any]:
    """The figures ``TARGETS`` names, from the parts that ran."""
    figures: dict[str, Any] = {}
    if "scenarios" in result:
        figures["scenarios_failed"] = sum(not r["passed"] for r in result["scenarios"])
    if "people" in result:
        worlds = result["people"].values()
        figures["people_contacts_moving"] = sum(w["contacts_moving"] for w in worlds)
        figures["people_reached_short"] = max(len(w["seeds"]) - w["reached_with_people"]
                                              for w in worlds)
        deltas = [w["lateral_rms_delta_m_max"] for w in worlds
                  if w["lateral_rms_delta_m_max"] is not None]
        figures["people_lateral_rms_delta_m_max"] = max(deltas) if deltas else None
        figures["blind_m_over_bound"] = round(max(
            w["blind_m_max"] for w in worlds) - result["lost_distance_m"] - BLIND_BRAKING_M, 3)
    if "e_stop" in result:
        figures["e_stop_latency_ms_p95"] = result["e_stop"]["latency_ms_p95"]
        figures["e_stop_at_rest_s_max"] = result["e_stop"]["at_rest_s_max"]
    if "governor" in result:
        figures["governor_frame_ms_p95"] = result["governor"]["frame_ms_p95"]
    return figures


def run(args: argparse.Namespace) -> int:
    """Print the safety benchmark's JSON (``vmnav bench safety``)."""
    from robot.config import EstimatorConfig
    from shared.errors import InputError

    if args.seeds < 1:
        raise InputError("--seeds", f"must be >= 1, got {args.seeds}")
    if args.people < 1:
        raise InputError("--people", f"must be >= 1, got {args.people}")
    if args.estops < 1:
        raise InputError("--estops", f"must be >= 1, got {args.estops}")
    parts = set(args.parts)
    out: Path = args.out
    result: dict[str, Any] = {"benchmark": "safety",
                              "lost_distance_m": EstimatorConfig().lost_distance_m}
    if "scenarios" in parts:
        result["scenarios"] = scenarios_part(out / "scenarios")
    if "people" in parts:
        result["people"] = people_part(args.worlds, range(args.seed, args.seed + args.seeds),
                                       args.people, out / "people", args)
    if "e_stop" in parts:
        result["e_stop"] = e_stop_part(out / "e_stop", args.estops)
    if "governor" in parts:
        result["governor"] = governor_part()
    result["summary"] = summary(result)
    print(json.dumps(result, indent=2))
    return 0
