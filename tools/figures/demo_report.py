"""What ``vmnav demo`` measures: errors against the taught path on ground truth, the report and
the lines it prints.

The taught trajectory is the polyline through the true poses of the route's key
images (:attr:`tools.harness.teach.TaughtMemory.true_poses`). The lateral error of a repeat
sample is its signed distance to that polyline (left positive), the heading error
its yaw minus the polyline's yaw interpolated at the closest point. The closest
segment is searched a few segments ahead of the previous one (progress is
monotonic; the first sample near the route's start), so a route that passes a
place twice is measured against the right pass; after a relocalization, samples are
measured against the route planned then, from the key image before its first on that
path (:func:`reference_ids`). Errors count after the first settling distance
(:func:`robot.control_law.settling_distance_m` of the start offset down to 5 cm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from robot.config import ControlConfig
from robot.control_law import settling_distance_m
from robot.mission import MissionState
from shared.pose import Pose2
from tools.harness.demo import RepeatRun
from tools.harness.teach import TaughtMemory

if TYPE_CHECKING:
    from shared.logs.writer import LogStats
    from sim.scene_change import ChangedWorld
    from tools.harness.ground_dispatch import DispatchResult

FloatArray = npt.NDArray[np.float64]

#: Segments searched ahead of the previous closest one.
_WINDOW = 8
#: The settling band, m.
SETTLED_M = 0.05


@dataclass(frozen=True, eq=False)
class TrackErrors:
    """Per-sample errors against the taught polyline.

    Attributes:
        lateral_m: (N,) signed distance, left positive, m.
        heading_rad: (N,) yaw minus the polyline's, rad in (-pi, pi].
        distance_m: (N,) true distance driven from the first sample, m.
    """

    lateral_m: FloatArray
    heading_rad: FloatArray
    distance_m: FloatArray


def _wrap(angle: FloatArray) -> FloatArray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def track_errors(poses_w: FloatArray, reference_w: FloatArray) -> TrackErrors:
    """Errors of a trajectory against a reference polyline.

    Args:
        poses_w: (N, 3) float64 true poses (x_m, y_m, yaw_rad), world frame, in time order.
        reference_w: (M, 3) float64 taught poses along the route, M >= 2.

    Returns:
        The errors (see the module docstring).
    """
    a, b = reference_w[:-1, :2], reference_w[1:, :2]
    ab = b - a
    length2 = np.maximum((ab**2).sum(axis=1), 1e-12)
    turn = _wrap(reference_w[1:, 2] - reference_w[:-1, 2])
    lateral, heading = np.zeros(len(poses_w)), np.zeros(len(poses_w))
    current: int | None = None
    for i, (x, y, yaw) in enumerate(poses_w):
        lo = 0 if current is None else current
        hi = min(lo + _WINDOW, len(ab))
        ap = np.array([x, y]) - a[lo:hi]
        t = np.clip((ap * ab[lo:hi]).sum(axis=1) / length2[lo:hi], 0.0, 1.0)
        offset = ap - t[:, None] * ab[lo:hi]
        dist = np.hypot(offset[:, 0], offset[:, 1])
        k = int(np.argmin(dist))
        current = lo + k
        side = np.sign(ab[current, 0] * ap[k, 1] - ab[current, 1] * ap[k, 0])
        lateral[i] = side * dist[k]
        heading[i] = _wrap(np.array(yaw - (reference_w[current, 2] + t[k] * turn[current])))
    steps = np.hypot(*np.diff(poses_w[:, :2], axis=0).T)
    return TrackErrors(lateral_m=lateral, heading_rad=heading,
                       distance_m=np.concatenate([[0.0], np.cumsum(steps)]))


def reference_ids(route: tuple[int, ...], taught: TaughtMemory) -> tuple[int, ...]:
    """The key images a plan is measured against: the route, after the key image before
    its first on that path (if any). A plan is made where the robot stands, between two
    key images of a path, and heads for the second: the taught path it follows there runs
    from the first. (Measured from the route's first key image alone, a robot relocalized
    1.5 m before it, on the taught path, was 1.5 m off: ``building`` seed 2.)"""
    first = taught.memory.keyframe(route[0])
    if first.index == 0:
        return route
    return (taught.memory.paths[first.path_id].keyframe_ids[first.index - 1], *route)


def plan_references(run: RepeatRun, taught: TaughtMemory) -> list[FloatArray]:
    """(M, 3) true poses of each plan's :func:`reference_ids`, in route order, one per plan
    (a relocalization plans again)."""
    routes: list[tuple[int, ...]] = []
    for sample in run.samples:
        route = sample.record.route
        if route and (not routes or routes[-1] != route):
            routes.append(route)
    return [np.array([taught.true_poses[k] for k in reference_ids(route, taught)],
                     dtype=np.float64) for route in routes]


def following_errors(run: RepeatRun, taught: TaughtMemory) -> TrackErrors | None:
    """Errors of the cycles spent following (and the arrival), each against the route
    planned when it ran; None when nothing was followed.

    The distance runs on across plans (the true distance driven while following).
    """
    moving = (MissionState.FOLLOWING, MissionState.ARRIVED)
    blocks: list[tuple[tuple[int, ...], list[Pose2]]] = []
    for sample in run.samples:
        record = sample.record
        if record.state not in moving or len(record.route) < 2:
            continue
        if not blocks or blocks[-1][0] != record.route:
            blocks.append((record.route, []))
        blocks[-1][1].append(sample.pose_w)
    parts = [track_errors(np.array(poses, dtype=np.float64),
                          np.array([taught.true_poses[k] for k in reference_ids(route, taught)],
                                   dtype=np.float64))
             for route, poses in blocks if len(poses) >= 2]
    if not parts:
        return None
    offsets = np.cumsum([0.0] + [p.distance_m[-1] for p in parts[:-1]])
    return TrackErrors(
        lateral_m=np.concatenate([p.lateral_m for p in parts]),
        heading_rad=np.concatenate([p.heading_rad for p in parts]),
        distance_m=np.concatenate([p.distance_m + o for p, o in zip(parts, offsets, strict=True)]))


def build_report(run: RepeatRun, taught: TaughtMemory, control: ControlConfig,
                 wall_time_s: float) -> dict[str, object]:
    """The ``report.json`` content (issue 4, item 7)."""
    result = run.result
    settle_m = settling_distance_m(control.pole_1_m, run.start_offset_m, SETTLED_M)
    follow = [s.record for s in run.samples if s.record.follow is not None]
    matches = [r.follow.vision.matches for r in follow
               if r.follow is not None and r.follow.vision is not None]
    loop_ms = np.array([r.compute_ns / 1e6 for r in follow])
    final = run.samples[-1].pose_w if run.samples else run.start_pose
    goal = taught.true_poses[run.goal_id]
    report: dict[str, object] = {
        "reached_goal": result.reached_goal,
        "state": result.state.value,
        "reason": result.reason,
        "detail": result.detail,
        "goal_key_image": run.goal_id,
        "start_pose": [round(v, 4) for v in run.start_pose],
        "final_position_error_m": _round(math.hypot(final[0] - goal[0], final[1] - goal[1])),
        "settling_distance_m": _round(settle_m),
        "key_images_route": result.targets,
        "key_images_reached": result.key_images_reached,
        "route": list(result.route),
        "sim_time_s": _round(run.sim_time_s),
        "wall_time_s": _round(wall_time_s),
        "mean_matches": _round(float(np.mean(matches))) if matches else None,
        "loop_ms_p50": _round(float(np.percentile(loop_ms, 50))) if loop_ms.size else None,
        "loop_ms_p95": _round(float(np.percentile(loop_ms, 95))) if loop_ms.size else None,
        "lost_events": sum(e.kind == "lost" for e in result.events),
        "scene_change": scene_change_report(run.changed),
        "events": [{"t_s": round(e.t_ns / 1e9, 3), "kind": e.kind, "reason": e.reason,
                    "detail": e.detail} for e in result.events],
    }
    report["plans"] = len(plan_references(run, taught))
    report.update(track_metrics(following_errors(run, taught), settle_m))
    return report


def scene_change_report(changed: ChangedWorld) -> dict[str, object]:
    """What changed since the teach (:mod:`sim.scene_change`), for ``report.json``."""
    change = changed.change
    lighting = change.lighting
    return {
        "light_scale": lighting.scale,
        "lamps_switched_off": len(changed.lamps_off),
        "daylight_hour": lighting.hour,
        "light_step": ({"factor": lighting.step_factor, "at_s": lighting.step_at_s}
                       if lighting.has_step else None),
        "moved_fraction": change.moved_fraction,
        "objects_moved": len(changed.moved),
        "objects_left_in_place": len(changed.stuck),
        "pictures_removed": changed.removed_pictures,
        "objects_removed": changed.removed_objects,
        "doors": {name: opening for name, opening in change.doors},
    }


def track_metrics(errors: TrackErrors | None, settle_m: float) -> dict[str, object]:
    """Distance followed, and lateral RMS / max and heading RMS of the samples beyond
    ``settle_m`` (None without any)."""
    empty: dict[str, object] = {"distance_m": 0.0, "lateral_rms_m": None,
                                "lateral_max_m": None, "heading_rms_deg": None}
    if errors is None:
        return empty
    settled = errors.distance_m >= settle_m
    if not settled.any():
        return {**empty, "distance_m": _round(float(errors.distance_m[-1]))}
    lateral, heading = errors.lateral_m[settled], errors.heading_rad[settled]
    return {
        "distance_m": _round(float(errors.distance_m[-1])),
        "lateral_rms_m": _round(float(np.sqrt(np.mean(lateral**2)))),
        "lateral_max_m": _round(float(np.abs(lateral).max())),
        "heading_rms_deg": _round(math.degrees(float(np.sqrt(np.mean(heading**2))))),
    }


def summary_text(report: dict[str, object]) -> str:
    """The short human summary ``vmnav demo`` prints."""
    outcome = "reached the goal" if report["reached_goal"] else "did NOT reach the goal"
    lines = [
        f"repeat: {outcome} key image {report['goal_key_image']} ({report['state']}: "
        f"{report['detail']})",
        f"  {report['key_images_reached']}/{report['key_images_route']} key images, "
        f"{fixed_text(report['distance_m'], 2)} m in "
        f"{fixed_text(report['sim_time_s'], 1)} s simulated, "
        f"{fixed_text(report['wall_time_s'], 1)} s wall",
    ]
    if report["lateral_rms_m"] is not None:
        lines.append(
            f"  after {fixed_text(report['settling_distance_m'], 2)} m settling: lateral RMS "
            f"{cm_text(report['lateral_rms_m'])} cm, max {cm_text(report['lateral_max_m'])} cm; "
            f"heading RMS {fixed_text(report['heading_rms_deg'], 2)} deg; final position error "
            f"{cm_text(report['final_position_error_m'])} cm")
    lines.append(f"  {fixed_text(report['mean_matches'], 1)} matches per frame on average; servo "
                 f"loop {fixed_text(report['loop_ms_p50'], 1)} ms median, "
                 f"{fixed_text(report['loop_ms_p95'], 1)} ms p95; "
                 f"{report['lost_events']} LOST events")
    return "\n".join(lines)


def hil_summary_text(report: dict[str, object], out: Path) -> str:
    """The summary ``vmnav demo --hil`` prints about its ``report`` written into ``out``."""
    reached = "reached" if report["reached_goal"] else "did NOT reach"
    return "\n".join([
        f"hil: taught {report['route']!r} by teleoperation over MAVLink "
        f"({report['key_images_taught']} key images, {report['teach_sim_time_s']:.0f} s); "
        f"the robot {reached} the goal key image {report['goal_key_image']} "
        f"in {report['repeat_sim_time_s']:.0f} s",
        f"  after {report['settling_distance_m']:.2f} m settling: lateral RMS "
        f"{cm_text(report['lateral_rms_m'])} cm, max {cm_text(report['lateral_max_m'])} cm; "
        f"heading RMS {fixed_text(report['heading_rms_deg'], 2)} deg; final position error "
        f"{cm_text(report['final_position_error_m'])} cm",
        f"  {report['key_images_reached']} key images reached, {report['mean_matches']} "
        f"matches per frame on average, {report['lost_events']} LOST events; servo loop "
        f"{fixed_text(report['loop_ms_p50'], 1)} ms median, "
        f"{fixed_text(report['loop_ms_p95'], 1)} ms p95 (robot log)",
        f"  mission upload to MISSION_ACK {report['mission_upload_ms']:.0f} ms; "
        f"{report['wall_time_s']:.0f} s wall; processes exited {report['exit_codes']}",
        f"wrote {out / 'report.json'}; logs in {out / 'logs'}, process outputs {out}/*.out"])


def dispatch_text(dispatch: DispatchResult, goal: int) -> str:
    """What the ground station did and saw, and where its log went (one or two lines)."""
    if dispatch.upload_ms is None:
        return f"ground station: goal not dispatched ({dispatch.error})"
    outcome = {True: "reached (MISSION_ITEM_REACHED)", False: "stopped short of it",
               None: f"no outcome seen ({dispatch.error or 'the demo ended first'})"}
    lines = [f"ground station: goal key image {goal} uploaded over UDP (MISSION_ACK after "
             f"{dispatch.upload_ms:.0f} ms), mission started; {outcome[dispatch.reached]}"]
    if dispatch.log_files:
        lines.append("ground log " + ", ".join(str(p) for p in dispatch.log_files))
    return "\n".join(lines)


def log_text(stats: LogStats | None) -> str:
    """Where the robot log went and what it holds, one line (``stats`` None: no cycle)."""
    if stats is None:
        return "log: none written (no cycle ran)"
    files = ", ".join(str(p) for p in stats.files) or "no file"
    problems = [f"{n} {what}" for n, what in ((stats.dropped, "dropped (writer behind)"),
                                              (stats.lost, "lost")) if n]
    if stats.last_error:
        problems.append(stats.last_error)
    return (f"log {files}: {stats.written} messages"
            + (f" ({'; '.join(problems)})" if problems else ""))


def cm_text(value: object) -> str:
    """A length in m as cm with one decimal ("n/a" for a missing value)."""
    return fixed_text(100 * value, 1) if isinstance(value, float | int) else "n/a"


def fixed_text(value: object, digits: int) -> str:
    """A number with ``digits`` decimals ("n/a" for a missing value)."""
    return f"{value:.{digits}f}" if isinstance(value, float | int) else "n/a"


def _round(value: float) -> float:
    return round(value, 4)
