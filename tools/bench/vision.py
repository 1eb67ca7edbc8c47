"""``vmnav bench vision``: the vision figures of issue 3, measured on the simulator.

The routes of a world are taught as ``vmnav teach`` does
(:func:`tools.harness.teach.teach_memory`: the human-like teach driver, key
image selection from the frames and the wheel odometry), keeping each key
image's true pose, which the memory itself does not know. Then:

* **State** (y, theta). Query poses are drawn between two consecutive key images
  of a taught path: a segment is chosen with probability proportional to its
  length (uniform in distance along the paths), a point of the straight line
  between the two key images' true positions, shifted sideways by
  U(-``max_offset_m``, ``max_offset_m``) and turned by
  U(-``max_yaw_deg``, ``max_yaw_deg``) from that line's direction; a pose where
  the robot would overlap a wall or furniture is drawn again. The view is
  rendered (the simulation advances one frame period first, so the illumination
  drifts) and the robot's per-frame pipeline runs on it: the front end's points
  inside the lens mask (``[features] method``), then
  :func:`robot.vision.frame_state.state_from_frame` (matching with the next key
  image, lifting, the three-view state, the image errors), with the key segment
  prepared once per key image
  (:func:`robot.vision.frame_state.key_segment_from_key_images`, with the teach
  tracks). The truth is the query's true pose in the next key image's true base
  frame (the definitions of :mod:`robot.vision.path_state`). Estimates that are
  not ok are counted, never dropped silently. The same queries are also run with
  the key pair matched directly (no teach tracks), for comparison, and both are
  split by key image spacing.
* **Frame time**: detection + :func:`~robot.vision.frame_state.state_from_frame`
  per query view on one core (the caller pins the process and holds OpenCV and
  BLAS to one thread), as CPU time of the thread (``time.thread_time_ns``: other
  processes sharing the core do not inflate it) and, beside it, wall-clock time;
  the key segment's preparation is reported apart (once per key image, not per
  frame).
* **Localization** (:func:`tools.bench.localize.measure_localization`): top-1
  rate on views within 0.3 m and 15 degrees of the paths, times for memories of
  300 and 3000 key images against the paper's exhaustive rule.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import operator
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from robot.config import PathStateConfig, VmnavConfig
from robot.segment_frame import relative_pose, wrap_angle
from robot.teach import SelectedKeyImage
from robot.vision.features import Features
from robot.vision.frame_state import (
    FrameState,
    KeySegment,
    key_segment_from_key_images,
    state_from_frame,
)
from robot.vision.front_end import FrontEnd, make_front_end
from shared.camera_model import CameraModel
from shared.config import CameraMountConfig
from shared.errors import ConfigError, DegenerateGeometryError
from shared.pose import Pose2
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.world import World, load_world
from tools.bench.localize import key_images_per_metre, measure_localization
from tools.bench.sim import versions
from tools.harness.teach import TaughtMemory, TaughtRoute, teach_memory

#: Issue 3's targets: figure -> (comparison, bound), beside the figures in the JSON.
TARGETS: dict[str, tuple[str, float]] = {
    "frame_fps_median": (">=", 50.0),
    "localize_ms_300": ("<", 50.0),
    "localize_ms_3000": ("<", 200.0),
    "localize_top1_rate": (">=", 0.97),
    "y_err_cm_median": ("<=", 2.0),
    "y_err_cm_p90": ("<=", 5.0),
    "theta_err_deg_median": ("<=", 0.5),
    "theta_err_deg_p90": ("<=", 1.5),
}
_COMPARISONS = {">=": operator.ge, "<=": operator.le, "<": operator.lt}
#: Key image spacings are reported apart below and above this, m (beyond about 0.5-0.6 m
#: matching the two key images directly was expected to degrade).
SPACING_SPLIT_M = 0.6
#: The paper's front end (Courbon et al. 2008: Harris corners, ZNCC), measured beside the
#: config's.
PAPER_METHOD = "harris-zncc"
#: Query poses tried per query before giving up.
_PLACEMENT_TRIES = 100
#: Frames run through the pipeline before timing (first-call costs).
_WARMUP_FRAMES = 3


@dataclass(frozen=True, slots=True)
class VisionBenchPlan:
    """How much ``vmnav bench vision`` measures.

    Attributes:
        routes: routes of the world to teach; None = all of them.
        state_queries: views for the y/theta figures and the frame time.
        localize_queries: views for the localization top-1 rate.
        exhaustive_queries: views timed with the exhaustive localization, per memory size.
        max_offset_m: lateral offset of the state queries from the path, up to, m.
        max_yaw_deg: heading of the state queries off the path's direction, up to, degrees.
        seed: seed of the query poses and the RANSAC samples.
    """

    routes: tuple[str, ...] | None = None
    state_queries: int = 300
    localize_queries: int = 200
    exhaustive_queries: int = 5
    max_offset_m: float = 0.5
    max_yaw_deg: float = 20.0
    seed: int = 0

    @classmethod
    def quick(cls, routes: tuple[str, ...] | None = None, seed: int = 0) -> VisionBenchPlan:
        """A small run (a test's): few queries, one exhaustive localization per size."""
        return cls(routes=routes, state_queries=12, localize_queries=10, exhaustive_queries=1,
                   seed=seed)


@dataclass(frozen=True, slots=True)
class Estimate:
    """The pipeline's answer for one query with one kind of key pair.

    Attributes:
        frame: the estimate; None when the two key images are too close (by
            odometry) for a key pair.
        key_pair_ok: the key pair gave a trustworthy structure.
    """

    frame: FrameState | None
    key_pair_ok: bool

    @property
    def ok(self) -> bool:
        """A usable state."""
        return self.frame is not None and self.frame.state.ok


@dataclass(frozen=True, slots=True)
class StateOutcome:
    """One state query against the truth.

    Attributes:
        route: the taught route.
        next_index: the next key image's index along its path.
        spacing_m: true distance between the segment's two key images, m.
        truth: (s_m, y_m, theta_rad) of the query in the next key image's true base frame.
        tracked: the estimate with the key pair from teach tracks + ZNCC (the pipeline's).
        direct: the same with the key pair from ZNCC matching alone.
        features_ms: corner detection time, ms (CPU time of the thread).
        state_ms: :func:`state_from_frame` time (with teach tracks), ms (CPU time).
        wall_ms: wall-clock time of both, ms (inflated when other processes share the core).
    """

    route: str
    next_index: int
    spacing_m: float
    truth: tuple[float, float, float]
    tracked: Estimate
    direct: Estimate
    features_ms: float
    state_ms: float
    wall_ms: float


@dataclass(frozen=True, slots=True)
class StateRun:
    """The state queries and the time the key segments took.

    Attributes:
        outcomes: one per query.
        key_segment_ms: time of each key segment prepared with teach tracks, ms.
        redraws: query poses drawn again because the robot would overlap something.
        key_pairs: :meth:`_Segments.summary` with teach tracks (``"with_teach_tracks"``)
            and without (``"matched_directly"``).
    """

    outcomes: tuple[StateOutcome, ...]
    key_segment_ms: tuple[float, ...]
    redraws: int
    key_pairs: dict[str, dict[str, Any]]


class _Segments:
    """Key segments prepared on first use (timed), with or without the teach tracks."""

    def __init__(self, front_end: FrontEnd, config: VmnavConfig, rng: np.random.Generator,
                 tracks: bool) -> None:
        self._front_end, self._config = front_end, config
        self._rng, self._tracks = rng, tracks
        self._cache: dict[tuple[str, int], KeySegment | None] = {}
        self.prepare_ms: list[float] = []

    def get(self, route: TaughtRoute, next_index: int) -> KeySegment | None:
        """The segment towards key image ``next_index`` from the one before (None: the
        two are too close for a key pair)."""
        key = (route.route.name, next_index)
        if key not in self._cache:
            previous, next_ = route.key_images[next_index - 1], route.key_images[next_index]
            tracks = next_.record.tracked_from_previous[:, ::-1] if self._tracks else None
            t0 = time.thread_time_ns()
            try:
                self._cache[key] = key_segment_from_key_images(
                    _features(self._front_end, next_), _features(self._front_end, previous),
                    next_.record.odom_pose, previous.record.odom_pose, self._front_end,
                    self._config.camera.mount, self._rng,
                    self._config.path_state, tracks,
                )
            except DegenerateGeometryError:
                self._cache[key] = None
            self.prepare_ms.append((time.thread_time_ns() - t0) / 1e6)
        return self._cache[key]

    def summary(self) -> dict[str, Any]:
        """Over the key pairs prepared: how many, how many not ok (or degenerate), the
        correspondences they were built from and the points they triangulated (medians)."""
        built = [s for s in self._cache.values() if s is not None]
        return {
            "key_pairs": len(self._cache),
            "key_pairs_not_ok": sum(s is None or not s.key_pair.ok for s in self._cache.values()),
            "correspondences_median": _median([len(s.correspondences.idx_next) for s in built]),
            "correspondences_min": min((len(s.correspondences.idx_next) for s in built),
                                       default=None),
            "points_median": _median([len(s.key_pair.feature_idx) for s in built]),
            "points_min": min((len(s.key_pair.feature_idx) for s in built), default=None),
        }


def bench_vision(
    config: VmnavConfig, sim_config: SimConfig, camera: CameraModel, plan: VisionBenchPlan
) -> dict[str, Any]:
    """Both rows: the config's front end, and the paper's (``harris-zncc``) beside it.

    Returns:
        The figures of the config's front end (:func:`bench_front_end`) with
        ``front_end`` (its method) and ``paper_front_end``: the same figures with
        ``[features] method = "harris-zncc"`` (absent when that is the config's).

    Raises:
        InputError: an unknown route, or a teach drive that does not reach its end.
        ConfigError: no free query pose found near the paths.
    """
    figures = bench_front_end(config, sim_config, camera, plan)
    result = {"front_end": config.features.method, **figures}
    if config.features.method != PAPER_METHOD:
        paper = dataclasses.replace(
            config, features=dataclasses.replace(config.features, method=PAPER_METHOD))
        result["paper_front_end"] = {"front_end": PAPER_METHOD,
                                     **bench_front_end(paper, sim_config, camera, plan)}
    return {**result, "versions": library_versions()}


def bench_front_end(
    config: VmnavConfig, sim_config: SimConfig, camera: CameraModel, plan: VisionBenchPlan
) -> dict[str, Any]:
    """Teach, then measure state accuracy, frame time and localization (module docstring),
    with the config's front end.

    Returns:
        JSON-ready figures (see ``vmnav bench vision --help`` and the module docstring),
        with ``targets`` and ``targets_met``.

    Raises:
        InputError: an unknown route, or a teach drive that does not reach its end.
        ConfigError: no free query pose found near the paths.
    """
    world = load_world(sim_config.world)
    names = list(plan.routes) if plan.routes else [r.name for r in world.routes]
    _say(config, f"teaching {', '.join(names)} in {world.name}")
    taught = teach_memory(world, names, config, sim_config, camera, join=False)
    _say(config, f"{plan.state_queries} state queries")
    run = run_state_queries(taught, world, config, sim_config, camera, plan)
    _say(config, f"{plan.localize_queries} localization queries")
    localization = measure_localization(taught, world, config, sim_config, camera,
                                        plan.localize_queries, plan.seed, plan.exhaustive_queries)
    localization["localize_failures"] = localization.pop("failures")
    figures = {
        "world": world.name,
        "routes": names,
        "plan": {"state_queries": plan.state_queries, "localize_queries": plan.localize_queries,
                 "exhaustive_queries": plan.exhaustive_queries,
                 "max_offset_m": plan.max_offset_m, "max_yaw_deg": plan.max_yaw_deg,
                 "seed": plan.seed},
        **memory_summary(taught),
        **frame_time_summary(run, camera),
        **state_summary(run),
        **localization,
    }
    return {**figures, **target_figures(figures)}


def library_versions() -> dict[str, str]:
    """The simulator benchmark's versions, plus the vision's own dependencies."""
    from importlib.metadata import version

    return {**versions(), **{name: version(name) for name in ("scipy", "poselib")}}


def target_figures(figures: dict[str, Any]) -> dict[str, Any]:
    """``targets`` (e.g. ``"frame_fps_median": ">= 50"``) and ``targets_met`` (False for a
    missing figure, e.g. no ok state estimate)."""
    met = {}
    for name, (comparison, bound) in TARGETS.items():
        value = figures.get(name)
        met[name] = value is not None and bool(_COMPARISONS[comparison](value, bound))
    return {
        "targets": {name: f"{comparison} {bound:g}" for name, (comparison, bound) in
                    TARGETS.items()},
        "targets_met": met,
    }


def memory_summary(taught: TaughtMemory) -> dict[str, Any]:
    """Key images, their density along the taught routes (odometry), their true spacing and
    the teach tracks they keep."""
    memory = taught.memory
    length_m = sum(memory.keyframes[p.keyframe_ids[-1]].distance_m for p in memory.paths.values())
    spacings = np.concatenate([_true_spacings(route) for route in taught.routes])
    tracks = [len(k.record.tracked_from_previous) for r in taught.routes for k in r.key_images[1:]]
    return {
        "keyframes": len(memory.keyframes),
        "taught_length_m": round(length_m, 2),
        "key_images_per_m": round(len(memory.keyframes) / length_m, 3),
        "key_images_per_m_by_route": key_images_per_metre(taught),
        "key_spacing_m_median": _round(np.median(spacings)),
        "key_spacing_m_p90": _round(np.percentile(spacings, 90)),
        "key_spacing_m_max": _round(spacings.max()),
        "teach_tracks_per_key_image_median": float(np.median(tracks)) if tracks else None,
    }


def _say(config: VmnavConfig, step: str) -> None:
    """A progress line on stderr: which front end, which step."""
    print(f"vmnav bench vision: {config.features.method}: {step}", file=sys.stderr, flush=True)


def run_state_queries(
    taught: TaughtMemory,
    world: World,
    config: VmnavConfig,
    sim_config: SimConfig,
    camera: CameraModel,
    plan: VisionBenchPlan,
) -> StateRun:
    """Render ``plan.state_queries`` views between key images and estimate their state."""
    sim = Simulation(world, sim_config)
    renderer = FisheyeRenderer.for_simulation(sim, camera)
    front_end = make_front_end(config.features, camera)
    pose_rng = np.random.default_rng([plan.seed, 1])
    ransac_rng = np.random.default_rng([plan.seed, 2])
    segments = _Segments(front_end, config, np.random.default_rng([plan.seed, 3]), True)
    direct_segments = _Segments(front_end, config, np.random.default_rng([plan.seed, 4]), False)
    mount, state_config = config.camera.mount, config.path_state
    _warm_up(taught, segments, config, front_end, ransac_rng)
    outcomes, redraws = [], 0
    for _ in range(plan.state_queries):
        route, next_index, pose, tries = _place_between_key_images(taught, sim, pose_rng, plan)
        redraws += tries - 1
        sim.step_until(sim.now_ns + sim_config.frame_period_ns)
        image = renderer.render(sim).image
        segment = segments.get(route, next_index)
        direct_segment = direct_segments.get(route, next_index)
        w0, t0 = time.perf_counter_ns(), time.thread_time_ns()
        current = front_end.describe(image)
        t1 = time.thread_time_ns()
        tracked = _estimate(current, segment, front_end, mount, ransac_rng, state_config)
        t2, w2 = time.thread_time_ns(), time.perf_counter_ns()
        direct = _estimate(current, direct_segment, front_end, mount, ransac_rng, state_config)
        outcomes.append(StateOutcome(
            route=route.route.name, next_index=next_index,
            spacing_m=float(_true_spacings(route)[next_index - 1]),
            truth=relative_pose(route.true_poses[next_index], pose),
            tracked=tracked, direct=direct,
            features_ms=(t1 - t0) / 1e6, state_ms=(t2 - t1) / 1e6, wall_ms=(w2 - w0) / 1e6,
        ))
    key_pairs = {"with_teach_tracks": segments.summary(),
                 "matched_directly": direct_segments.summary()}
    return StateRun(tuple(outcomes), tuple(segments.prepare_ms), redraws, key_pairs)


def frame_time_summary(run: StateRun, camera: CameraModel) -> dict[str, Any]:
    """Per-frame time (detection + matching + lifting + state + image errors), and the key
    segment's (once per key image)."""
    features_ms = np.array([o.features_ms for o in run.outcomes])
    state_ms = np.array([o.state_ms for o in run.outcomes])
    frame_ms = features_ms + state_ms
    wall_ms = np.array([o.wall_ms for o in run.outcomes])
    return {
        "frames_timed": len(frame_ms),
        "image_size": [camera.width, camera.height],
        "frame_fps_median": round(1000.0 / float(np.median(frame_ms)), 1),
        "frame_ms_median": _round(np.median(frame_ms)),
        "frame_ms_p95": _round(np.percentile(frame_ms, 95)),
        "features_ms_median": _round(np.median(features_ms)),
        "state_ms_median": _round(np.median(state_ms)),
        "frame_wall_ms_median": _round(np.median(wall_ms)),
        "frame_wall_ms_p95": _round(np.percentile(wall_ms, 95)),
        "key_segment_ms_median": _round(np.median(run.key_segment_ms)),
    }


def state_summary(run: StateRun) -> dict[str, Any]:
    """y/theta errors of the estimates with teach tracks (the pipeline's), split by key
    image spacing, and the same for the key pair matched directly."""
    outcomes = run.outcomes
    wide = [o.spacing_m > SPACING_SPLIT_M for o in outcomes]

    def by_spacing(pick: str) -> dict[str, Any]:
        return {
            f"spacing <= {SPACING_SPLIT_M} m": error_figures(
                [(getattr(o, pick), o.truth) for o, w in zip(outcomes, wide, strict=True)
                 if not w]),
            f"spacing > {SPACING_SPLIT_M} m": error_figures(
                [(getattr(o, pick), o.truth) for o, w in zip(outcomes, wide, strict=True) if w]),
        }

    return {
        **error_figures([(o.tracked, o.truth) for o in outcomes]),
        "state_pose_redraws": run.redraws,
        "key_pairs": run.key_pairs,
        "state_by_key_spacing": by_spacing("tracked"),
        "state_key_pair_matched_directly": {
            **error_figures([(o.direct, o.truth) for o in outcomes]),
            "by_key_spacing": by_spacing("direct"),
        },
    }


def error_figures(rows: Sequence[tuple[Estimate, tuple[float, float, float]]]
                  ) -> dict[str, Any]:
    """|y| and |theta| errors of the ok estimates (median, p90, max), and the counts.

    Args:
        rows: (estimate, true (s_m, y_m, theta_rad)) per query.

    Returns:
        ``state_queries``, ``state_not_ok`` (failures, of which ``key_pair_not_ok`` had
        no usable key pair), ``y_err_cm_*`` and ``theta_err_deg_*`` over the ok
        estimates (None without any), ``state_matches_median``.
    """
    ok = [(r.frame.state, truth) for r, truth in rows if r.ok and r.frame is not None]
    y_cm = np.array([abs(st.y_m - truth[1]) * 100.0 for st, truth in ok])
    theta_deg = np.array([abs(math.degrees(wrap_angle(st.theta_rad - truth[2])))
                          for st, truth in ok])

    def stat(values: np.ndarray, q: float) -> float | None:
        return _round(np.percentile(values, q)) if values.size else None

    return {
        "state_queries": len(rows),
        "state_not_ok": len(rows) - len(ok),
        "key_pair_not_ok": sum(not r.key_pair_ok for r, _ in rows),
        "y_err_cm_median": stat(y_cm, 50),
        "y_err_cm_p90": stat(y_cm, 90),
        "y_err_cm_max": stat(y_cm, 100),
        "theta_err_deg_median": stat(theta_deg, 50),
        "theta_err_deg_p90": stat(theta_deg, 90),
        "theta_err_deg_max": stat(theta_deg, 100),
        "state_matches_median": stat(
            np.array([r.frame.matches for r, _ in rows if r.frame is not None]), 50),
    }


def _estimate(current: Features, segment: KeySegment | None, front_end: FrontEnd,
              mount: CameraMountConfig, rng: np.random.Generator, config: PathStateConfig
              ) -> Estimate:
    if segment is None:
        return Estimate(frame=None, key_pair_ok=False)
    return Estimate(frame=state_from_frame(current, segment, front_end, mount, rng, config),
                    key_pair_ok=segment.key_pair.ok)


def _features(front_end: FrontEnd, key: SelectedKeyImage) -> Features:
    """A selected key image's stored features, as the follower reads them from a memory."""
    record = key.record
    return front_end.features(record.pixels_xy, front_end.descriptors_from_stored(record.patches))


def _true_spacings(route: TaughtRoute) -> np.ndarray:
    """(n - 1,) true distances between consecutive key images of a taught route, m."""
    positions = np.array(route.true_poses)[:, :2]
    return np.hypot(*np.diff(positions, axis=0).T)


def _place_between_key_images(
    taught: TaughtMemory, sim: Simulation, rng: np.random.Generator, plan: VisionBenchPlan
) -> tuple[TaughtRoute, int, Pose2, int]:
    """Draw a free query pose between two key images (module docstring) and place the robot.

    Returns:
        The route, the next key image's index, the pose, and the draws it took.

    Raises:
        ConfigError: no free pose in many draws.
    """
    segments = [(route, k) for route in taught.routes for k in range(1, len(route.key_images))]
    lengths = np.array([_true_spacings(route)[k - 1] for route, k in segments])
    if not segments or lengths.sum() <= 0.0:
        raise ConfigError("state queries", "the taught paths have no length to query along")
    for tries in range(1, _PLACEMENT_TRIES + 1):
        route, k = segments[int(rng.choice(len(segments), p=lengths / lengths.sum()))]
        (xa, ya, _), (xb, yb, _) = route.true_poses[k - 1], route.true_poses[k]
        direction = math.atan2(yb - ya, xb - xa)
        t = rng.uniform(0.0, 1.0)
        offset = rng.uniform(-plan.max_offset_m, plan.max_offset_m)
        yaw = wrap_angle(direction + math.radians(rng.uniform(-plan.max_yaw_deg,
                                                              plan.max_yaw_deg)))
        pose = Pose2(xa + t * (xb - xa) - offset * math.sin(direction),
                     ya + t * (yb - ya) + offset * math.cos(direction), yaw)
        try:
            sim.place_robot(pose)
        except ConfigError:
            continue
        return route, k, pose, tries
    raise ConfigError("state queries", f"no free pose near the paths in {_PLACEMENT_TRIES} tries")


def _warm_up(taught: TaughtMemory, segments: _Segments, config: VmnavConfig,
             front_end: FrontEnd, rng: np.random.Generator) -> None:
    """Run the pipeline on a few key images first, so that first-call costs are not timed."""
    route = taught.routes[0]
    segment = segments.get(route, 1) if len(route.key_images) > 1 else None
    if segment is not None:
        for key in route.key_images[:_WARMUP_FRAMES]:
            state_from_frame(front_end.describe(key.record.image), segment, front_end,
                             config.camera.mount, rng, config.path_state)
    segments.prepare_ms.clear()


def _round(value: float | np.floating[Any]) -> float:
    return round(float(value), 3)


def _median(values: Sequence[float]) -> float | None:
    return _round(np.median(values)) if len(values) else None


def run(args: argparse.Namespace) -> int:
    """Print the vision benchmark's JSON (``vmnav bench vision``)."""
    from robot.config import load_config
    from shared.errors import InputError
    from tools.bench.cpu import pin_to_one_core
    from tools.harness.sim_args import sim_config_from_args

    sim_config, camera = sim_config_from_args(args)
    config = load_config(args.config)
    routes = tuple(args.routes) if args.routes else None
    plan = (VisionBenchPlan.quick(routes, args.query_seed) if args.quick
            else VisionBenchPlan(routes=routes, seed=args.query_seed))
    for name in ("state_queries", "localize_queries"):
        value = getattr(args, name)
        if value is not None:
            if value < 1:
                raise InputError(f"--{name.replace('_', '-')}", f"must be >= 1, got {value}")
            plan = dataclasses.replace(plan, **{name: value})
    cpus = pin_to_one_core()
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_vision(config, sim_config, camera, plan)
    print(json.dumps({"benchmark": "vision", "cpus": cpus, "load_average_at_start": load,
                      **result}, indent=2))
    return 0
