"""The state estimate on simulator frames: render key images and current views from
known poses in the ``lab`` corridor, detect and match with the robot's front end, and
compare y and theta with the truth (tests may import sim/)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.vision.bearings import level_bearings
from robot.vision.features import Features, detect_harris
from robot.vision.key_pair import key_pair_geometry
from robot.vision.lens_mask import lens_mask
from robot.vision.matching import match_zncc
from robot.vision.path_state import PathState, state_from_views
from robot.vision.synthetic_scene import Pose2D, compose
from shared.camera_model import CameraModel
from shared.camera_mount import rotation_level_cam
from shared.config import FeatureConfig, MatchConfig, PathStateConfig, SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.world import Pose2, load_world

CAMERA = CameraModel.default()
#: Key images about 0.5 m apart (the teach default gives about two per metre); a window
#: wide enough for 20 degrees of yaw and 0.5 m of offset.
SPACING_M = 0.5
MATCHING = MatchConfig(search_radius_px=120.0)


class _Views:
    def __init__(self) -> None:
        self.config = SimConfig()
        self.sim = Simulation(load_world("lab"), self.config)
        self.renderer = FisheyeRenderer.for_simulation(self.sim, CAMERA)
        self.mask = lens_mask(CAMERA)

    def features(self, pose: Pose2D) -> Features:
        self.sim.place_robot(Pose2(pose[0], pose[1], math.degrees(pose[2])))
        return detect_harris(self.renderer.render(self.sim).image, FeatureConfig(), self.mask)


@pytest.fixture(scope="module")
def views() -> _Views:
    return _Views()


def _state(views: _Views, previous: Pose2D, next_: Pose2D, current: Pose2D,
           rng: np.random.Generator) -> PathState:
    mount, config = views.config.camera, PathStateConfig()
    R = rotation_level_cam(mount)
    f_prev, f_next, f_cur = (views.features(p) for p in (previous, next_, current))

    def bearings(f: Features, idx: np.ndarray) -> np.ndarray:
        lifted = level_bearings(CAMERA, f.pixels_xy[idx], R)
        assert lifted.valid.all()
        return lifted.bearings

    m = match_zncc(f_next, f_prev, MATCHING)
    # Teach odometry: the true poses with a 1 % scale error on the spacing.
    odom_next = compose(previous, (1.01 * SPACING_M, 0.0, next_[2] - previous[2]))
    pair = key_pair_geometry(bearings(f_next, m.idx_a), bearings(f_prev, m.idx_b), m.idx_a,
                             odom_next, previous, mount, rng, config)
    c = match_zncc(f_cur, f_next, MATCHING)
    return state_from_views(bearings(f_cur, c.idx_a), bearings(f_next, c.idx_b), c.idx_b, pair,
                            mount, rng, config)


def lab_state_errors(views: _Views, rng: np.random.Generator, segments: tuple[float, ...],
                     per_segment: int) -> tuple[list[float], list[float], int]:
    """|y| errors (m) and |theta| errors (degrees) of the ok states, and the not-ok count.

    Each segment of the main corridor (y = 10 m, 2 m wide) starts at x = ``segments[i]``;
    current poses are drawn between its two key images within 0.4 m and 20 degrees.
    For a larger run than the test's (100 poses, about 5 s)::

        lab_state_errors(_Views(), np.random.default_rng(0), tuple(np.arange(3.0, 25.0, 1.1)), 5)
    """
    y_err, theta_err, not_ok = [], [], 0
    for x0 in segments:
        previous: Pose2D = (x0, 10.0, 0.0)
        next_ = compose(previous, (SPACING_M, 0.0, math.radians(1.0)))
        for _ in range(per_segment):
            s = float(rng.uniform(-SPACING_M, 0.0))
            y = float(rng.uniform(-0.4, 0.4))
            theta = math.radians(float(rng.uniform(-20.0, 20.0)))
            st = _state(views, previous, next_, compose(next_, (s, y, theta)), rng)
            if not st.ok:
                not_ok += 1
                continue
            y_err.append(abs(st.y_m - y))
            theta_err.append(abs(math.degrees(st.theta_rad - theta)))
    return y_err, theta_err, not_ok


def test_y_and_theta_on_rendered_frames(views: _Views, rng: np.random.Generator) -> None:
    y_err, theta_err, not_ok = lab_state_errors(views, rng, (5.0, 13.0, 21.0), 3)
    assert not_ok == 0
    assert np.median(y_err) <= 0.02 and max(y_err) <= 0.05
    assert np.median(theta_err) <= 0.5 and max(theta_err) <= 1.5
