"""Benchmark of the state estimate (y, theta) on synthetic corridor scenes (one core).

Each run draws a :func:`sim.synthetic.corridor_scene.corridor_scene` (default: key
images 0.6-1.5 m apart, walls 1.1-1.6 m from the centre line, the current pose
within 0.5 m and 20 degrees of the path between the previous and next key
images, 1 px noise, 20 % outliers, 1 % odometric scale error) and estimates the
state three ways:

* ``three_view_previous``: key pair (previous, next), the paper's configuration;
* ``three_view_after_next``: key pair (after next, next), the first segment's fallback;
* ``two_view_odometry``: the current-next relative pose scaled by the true distance
  between the optical centres times ``1 + N(0, two_view_distance_sigma)``, a stand-in
  for the odometry since the previous key image.

Errors are absolute differences from the truth; times are CPU times of the
calling thread (``time.thread_time_ns``), so other processes on the machine do
not inflate them. ``state_ms`` covers lifting the matched pixels of the current
frame and the state estimate (what runs per frame); ``key_pair_ms`` lifting and
the key pair (once per segment).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from robot.config import PathStateConfig
from robot.vision.bearings import level_bearings
from robot.vision.key_pair import KeyPairGeometry, key_pair_geometry
from robot.vision.path_state import PathState, state_from_two_views, state_from_views
from shared.camera_mount import rotation_level_cam
from shared.pose import Pose2
from sim.synthetic.corridor_scene import CorridorScene, SceneMatches, SceneView, corridor_scene

#: Errors larger than this count as gross failures, m and degrees.
GROSS_Y_M = 0.10
GROSS_THETA_DEG = 5.0


def bench_state(runs: int = 200, seed: int = 0, config: PathStateConfig | None = None,
                two_view_distance_sigma: float = 0.05, **scene: Any) -> dict[str, Any]:
    """Accuracy and time of the state estimators on ``runs`` synthetic scenes.

    Args:
        runs: scenes drawn.
        seed: seed of the scenes and of the RANSAC samples.
        config: thresholds; None = defaults.
        two_view_distance_sigma: relative error of the distance given to the two-view estimate.
        **scene: keyword arguments for :func:`corridor_scene` (e.g. ``noise_px``).

    Returns:
        JSON-ready: per estimator ``ok_rate``, ``y_err_cm_median``, ``y_err_cm_p90``,
        ``theta_err_deg_median``, ``theta_err_deg_p90``, ``gross_failures`` (ok
        estimates off by more than 10 cm or 5 degrees), ``state_ms_median``,
        ``state_ms_p95``, plus ``key_pair_ms_median`` for the three-view ones.
    """
    config = config or PathStateConfig()
    rng = np.random.default_rng(seed)
    rows: dict[str, list[tuple[PathState, CorridorScene, float, float]]] = {
        "three_view_previous": [], "three_view_after_next": [], "two_view_odometry": [],
    }
    for _ in range(runs):
        scene_k = corridor_scene(rng, **scene)
        for name, other, matches in (
            ("three_view_previous", scene_k.previous, scene_k.previous_next),
            ("three_view_after_next", scene_k.after, scene_k.after_next),
        ):
            key_pair, key_pair_ns = _timed(_key_pair, scene_k, other, matches, rng, config)
            state, state_ns = _timed(_three_view, scene_k, key_pair, rng, config)
            rows[name].append((state, scene_k, key_pair_ns / 1e6, state_ns / 1e6))
        distance = _centre_distance(scene_k) * (1.0 + rng.normal(0.0, two_view_distance_sigma))
        state, state_ns = _timed(_two_view, scene_k, max(distance, 0.0), rng, config)
        rows["two_view_odometry"].append((state, scene_k, math.nan, state_ns / 1e6))
    return {"runs": runs, "seed": seed, **{name: _summary(r) for name, r in rows.items()}}


def _timed(fn: Callable[..., Any], *args: Any) -> tuple[Any, int]:
    t0 = time.thread_time_ns()
    result = fn(*args)
    return result, time.thread_time_ns() - t0


def _bearings(s: CorridorScene, view: SceneView, idx: np.ndarray) -> np.ndarray:
    return level_bearings(s.camera, view.pixels_xy[idx], rotation_level_cam(s.mount)).bearings


def _key_pair(s: CorridorScene, other: SceneView, m: SceneMatches, rng: np.random.Generator,
              config: PathStateConfig) -> KeyPairGeometry:
    odom_other = s.odom_previous if other is s.previous else s.odom_after
    return key_pair_geometry(_bearings(s, s.next, m.idx_next), _bearings(s, other, m.idx_view),
                             m.idx_next, s.odom_next, odom_other, s.mount, rng, config)


def _three_view(s: CorridorScene, key_pair: KeyPairGeometry, rng: np.random.Generator,
                config: PathStateConfig) -> PathState:
    m = s.current_next
    return state_from_views(_bearings(s, s.current, m.idx_view), _bearings(s, s.next, m.idx_next),
                            m.idx_next, key_pair, s.mount, rng, config)


def _two_view(s: CorridorScene, distance_m: float, rng: np.random.Generator,
              config: PathStateConfig) -> PathState:
    m = s.current_next
    return state_from_two_views(_bearings(s, s.current, m.idx_view),
                                _bearings(s, s.next, m.idx_next), distance_m, s.mount, rng, config)


def _centre_distance(s: CorridorScene) -> float:
    """True distance between the current and next optical centres, m."""
    def centre(pose: Pose2) -> np.ndarray:
        x, y, yaw = pose
        return np.array([x + s.mount.x_m * math.cos(yaw) - s.mount.y_m * math.sin(yaw),
                         y + s.mount.x_m * math.sin(yaw) + s.mount.y_m * math.cos(yaw)])

    return float(np.linalg.norm(centre(s.current.pose_w) - centre(s.next.pose_w)))


def _summary(rows: list[tuple[PathState, CorridorScene, float, float]]) -> dict[str, float]:
    ok = [(st, s) for st, s, _, _ in rows if st.ok]
    y_cm = np.array([abs(st.y_m - s.y_m) * 100.0 for st, s in ok])
    theta_deg = np.array([abs(math.degrees(st.theta_rad - s.theta_rad)) for st, s in ok])
    state_ms = np.array([r[3] for r in rows])
    key_pair_ms = np.array([r[2] for r in rows])

    def stat(values: np.ndarray, q: float) -> float:
        return round(float(np.percentile(values, q)), 3) if values.size else math.nan

    out = {
        "ok_rate": round(len(ok) / max(len(rows), 1), 4),
        "y_err_cm_median": stat(y_cm, 50), "y_err_cm_p90": stat(y_cm, 90),
        "theta_err_deg_median": stat(theta_deg, 50), "theta_err_deg_p90": stat(theta_deg, 90),
        "gross_failures": int(np.count_nonzero((y_cm > 100.0 * GROSS_Y_M)
                                               | (theta_deg > GROSS_THETA_DEG))),
        "state_ms_median": stat(state_ms, 50), "state_ms_p95": stat(state_ms, 95),
    }
    if np.all(np.isfinite(key_pair_ms)):
        out["key_pair_ms_median"] = stat(key_pair_ms, 50)
    return out
