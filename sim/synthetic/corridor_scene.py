"""Synthetic corridor scenes with known poses, for tests and benchmarks of the geometry.

A straight corridor along the world x axis (floor z = 0, walls at y = +-W/2,
ceiling at z = H) is dotted with points on the walls, the floor and the ceiling.
A robot taught the corridor left key images at x = -d (previous), 0 (next) and
+d (after next), each a few centimetres and degrees off the centre line (the
teacher's wobble). The current robot pose lies between the previous and next key
images, off the path by up to ``max_offset_m`` and ``max_yaw_deg``, expressed in
the next key image's base frame as the state (s, y, theta) of DESIGN.md sec. 5.5.

Each view keeps the points that project validly through the camera model, with
Gaussian pixel noise; matches pair a view's features with the next key image's
by point id, and a fraction of them is then re-paired at random (outliers).
Teach odometry carries a scale error and a heading error like the simulator's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.camera_mount import camera_pose_world
from shared.config import CameraMountConfig
from shared.pose import Pose2

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SceneView:
    """One camera view of the scene.

    Attributes:
        pose_w: true base pose in the world.
        pixels_xy: (N, 2) float64 observed pixels (with noise), px.
        point_ids: (N,) int64 index into ``CorridorScene.points_w`` of each feature.
    """

    pose_w: Pose2
    pixels_xy: FloatArray
    point_ids: npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class SceneMatches:
    """Matches of some view's features with the next key image's features.

    Attributes:
        idx_view: (K,) int64 feature indices in the view.
        idx_next: (K,) int64 feature indices in the next key image.
        outlier: (K,) bool, the pair was re-paired at random (not the same point).
    """

    idx_view: npt.NDArray[np.int64]
    idx_next: npt.NDArray[np.int64]
    outlier: npt.NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class CorridorScene:
    """A corridor, three key images and a current view, with the truth.

    Attributes:
        camera: the lens.
        mount: the camera on the robot.
        points_w: (P, 3) float64 scene points, world frame, m.
        previous, next, after, current: the views (key images i, i+1, i+2, and now).
        odom_previous, odom_next, odom_after: teach odometry base poses of the key
            images (one odometry frame, with odometry errors), (x_m, y_m, yaw_rad).
        previous_next, after_next, current_next: matches of each view with the next key image.
        y_m: true lateral offset of the current base from the next key image's line, left +, m.
        theta_rad: true current yaw minus the next key image's yaw, rad.
        s_m: true along-track position of the current base relative to the next key image, m.
    """

    camera: CameraModel
    mount: CameraMountConfig
    points_w: FloatArray
    previous: SceneView
    next: SceneView
    after: SceneView
    current: SceneView
    odom_previous: Pose2
    odom_next: Pose2
    odom_after: Pose2
    previous_next: SceneMatches
    after_next: SceneMatches
    current_next: SceneMatches
    y_m: float
    theta_rad: float
    s_m: float


def compose(pose: Pose2, delta: Pose2) -> Pose2:
    """Planar pose composition ``pose (+) delta`` (delta in pose's frame)."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    return Pose2(x + c * delta[0] - s * delta[1], y + s * delta[0] + c * delta[1], yaw + delta[2])


def _corridor_points(rng: np.random.Generator, n: int, half_width: float, height: float,
                     x_range: tuple[float, float]) -> FloatArray:
    """n points: 60 % on the two walls, 20 % on the floor, 20 % on the ceiling."""
    kind = rng.choice(3, size=n, p=(0.6, 0.2, 0.2))
    x = rng.uniform(*x_range, n)
    side = rng.choice((-1.0, 1.0), n)
    wall = np.column_stack([x, side * half_width, rng.uniform(0.05, height - 0.05, n)])
    across = rng.uniform(-half_width + 0.05, half_width - 0.05, n)
    floor = np.column_stack([x, across, np.zeros(n)])
    ceiling = np.column_stack([x, across, np.full(n, height)])
    return np.where((kind == 0)[:, None], wall, np.where((kind == 1)[:, None], floor, ceiling))


def _view(rng: np.random.Generator, camera: CameraModel, mount: CameraMountConfig,
          points_w: FloatArray, pose_w: Pose2, noise_px: float) -> SceneView:
    T = camera_pose_world(pose_w, mount)
    points_c = (points_w - T[:3, 3]) @ T[:3, :3]
    pixels, valid = camera.project(points_c)
    pixels = pixels + rng.normal(0.0, noise_px, pixels.shape)
    _, still_valid = camera.lift(np.where(valid[:, None], pixels, 0.0))
    keep = np.flatnonzero(valid & still_valid)
    order = rng.permutation(keep.size)  # feature order carries no information
    return SceneView(pose_w=pose_w, pixels_xy=pixels[keep[order]], point_ids=keep[order])


def _matches(rng: np.random.Generator, view: SceneView, key: SceneView,
             outlier_ratio: float) -> SceneMatches:
    common, idx_view, idx_next = np.intersect1d(view.point_ids, key.point_ids, return_indices=True)
    outlier = rng.random(common.size) < outlier_ratio
    n_out = int(np.count_nonzero(outlier))
    if n_out:
        # Re-pair with a random other feature of the key image (never the right one).
        shift = rng.integers(1, len(key.point_ids), n_out)
        wrong = (idx_next[outlier] + shift) % len(key.point_ids)
        idx_next = idx_next.copy()
        idx_next[outlier] = wrong
        outlier[outlier] = key.point_ids[wrong] != view.point_ids[idx_view[outlier]]
    return SceneMatches(idx_view=idx_view.astype(np.int64), idx_next=idx_next.astype(np.int64),
                        outlier=outlier)


def _odometry(rng: np.random.Generator, start: Pose2, true_from: Pose2, true_to: Pose2,
              scale_sigma: float, yaw_sigma_rad: float) -> Pose2:
    """``start`` composed with the true relative motion, its length and heading perturbed."""
    dx, dy = true_to[0] - true_from[0], true_to[1] - true_from[1]
    c, s = math.cos(true_from[2]), math.sin(true_from[2])
    forward, left = c * dx + s * dy, -s * dx + c * dy
    scale = 1.0 + rng.normal(0.0, scale_sigma)
    dyaw = true_to[2] - true_from[2] + rng.normal(0.0, yaw_sigma_rad)
    return compose(start, Pose2(scale * forward, scale * left, dyaw))


def corridor_scene(
    rng: np.random.Generator,
    camera: CameraModel | None = None,
    mount: CameraMountConfig | None = None,
    *,
    n_points: int = 300,
    spacing_m: tuple[float, float] = (0.6, 1.5),
    width_m: tuple[float, float] = (2.2, 3.2),
    height_m: float = 2.5,
    max_offset_m: float = 0.5,
    max_yaw_deg: float = 20.0,
    teach_wobble: tuple[float, float] = (0.05, 3.0),
    noise_px: float = 1.0,
    outlier_ratio: float = 0.2,
    odometry_scale_sigma: float = 0.01,
    odometry_yaw_sigma_deg: float = 0.5,
) -> CorridorScene:
    """Draw a corridor scene (see the module docstring).

    Args:
        rng: source of all randomness.
        camera: the lens; None = ``CameraModel.default()``.
        mount: the camera on the robot; None = ``CameraMountConfig()``.
        n_points: scene points drawn (each view sees those in its field of view).
        spacing_m: key-image spacing d is uniform in this range, m.
        width_m: corridor width W is uniform in this range, m.
        height_m: ceiling height, m.
        max_offset_m: |y| of the current pose is uniform up to this, m.
        max_yaw_deg: |theta| of the current pose is uniform up to this, degrees.
        teach_wobble: key images are off the centre line by up to (m, degrees).
        noise_px: standard deviation of the pixel noise on each coordinate, px.
        outlier_ratio: fraction of matches re-paired at random.
        odometry_scale_sigma: relative error of each odometric key-image spacing.
        odometry_yaw_sigma_deg: error of each odometric heading change, degrees.

    Returns:
        The scene with its ground truth.
    """
    camera = camera or CameraModel.default()
    mount = mount or CameraMountConfig()
    d = float(rng.uniform(*spacing_m))
    half_width = 0.5 * float(rng.uniform(*width_m))
    wobble_m, wobble_rad = teach_wobble[0], math.radians(teach_wobble[1])

    def key_pose(x: float) -> Pose2:
        return Pose2(x, float(rng.uniform(-wobble_m, wobble_m)),
                     float(rng.uniform(-wobble_rad, wobble_rad)))

    pose_previous, pose_next, pose_after = key_pose(-d), key_pose(0.0), key_pose(d)
    s = float(rng.uniform(-d, 0.0))
    y = float(rng.uniform(-max_offset_m, max_offset_m))
    theta = float(rng.uniform(-math.radians(max_yaw_deg), math.radians(max_yaw_deg)))
    pose_current = compose(pose_next, Pose2(s, y, theta))
    points_w = _corridor_points(rng, n_points, half_width, height_m, (-d - 6.0, d + 8.0))
    previous, next_, after, current = (
        _view(rng, camera, mount, points_w, pose, noise_px)
        for pose in (pose_previous, pose_next, pose_after, pose_current)
    )
    yaw_sigma = math.radians(odometry_yaw_sigma_deg)
    odom_previous = Pose2(0.0, 0.0, 0.0)
    odom_next = _odometry(rng, odom_previous, pose_previous, pose_next, odometry_scale_sigma,
                          yaw_sigma)
    odom_after = _odometry(rng, odom_next, pose_next, pose_after, odometry_scale_sigma, yaw_sigma)
    return CorridorScene(
        camera=camera, mount=mount, points_w=points_w,
        previous=previous, next=next_, after=after, current=current,
        odom_previous=odom_previous, odom_next=odom_next, odom_after=odom_after,
        previous_next=_matches(rng, previous, next_, outlier_ratio),
        after_next=_matches(rng, after, next_, outlier_ratio),
        current_next=_matches(rng, current, next_, outlier_ratio),
        y_m=y, theta_rad=theta, s_m=s,
    )
