"""The state estimate on simulator frames: render key images and current views from
known poses in the ``lab`` corridor, run the robot's per-frame pipeline
(:mod:`robot.vision.frame_state`), and compare y and theta with the truth (tests may
import sim/). ``vmnav bench vision`` measures the same on key images taught in the
simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import FeatureConfig, PathStateConfig
from robot.vision.features import Features
from robot.vision.frame_state import key_segment_from_key_images, state_from_frame
from robot.vision.front_end import make_front_end
from robot.vision.path_state import PathState
from shared.camera_model import CameraModel
from shared.pose import Pose2
from sim.config import SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from sim.synthetic.corridor_scene import compose
from sim.world import load_world

CAMERA = CameraModel.default()
FRONT_END = make_front_end(FeatureConfig(), CAMERA)
#: Key images about 0.5 m apart (the teach default gives about two per metre).
SPACING_M = 0.5


class _Views:
    def __init__(self) -> None:
        self.config = SimConfig()
        self.sim = Simulation(load_world("lab"), self.config)
        self.renderer = FisheyeRenderer.for_simulation(self.sim, CAMERA)

    def features(self, pose: Pose2) -> Features:
        self.sim.place_robot(pose)
        return FRONT_END.describe(self.renderer.render(self.sim).image)


@pytest.fixture(scope="module")
def views() -> _Views:
    return _Views()


def _state(views: _Views, previous: Pose2, next_: Pose2, current: Pose2,
           rng: np.random.Generator) -> PathState:
    mount, config = views.config.camera_mount, PathStateConfig()
    f_prev, f_next, f_cur = (views.features(p) for p in (previous, next_, current))
    # Teach odometry: the true poses with a 1 % scale error on the spacing. No teach
    # tracks: the key images are matched directly.
    odom_next = compose(previous, (1.01 * SPACING_M, 0.0, next_[2] - previous[2]))
    segment = key_segment_from_key_images(f_next, f_prev, odom_next, previous, FRONT_END, mount,
                                          rng, config)
    return state_from_frame(f_cur, segment, FRONT_END, mount, rng, config).state


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
        previous = Pose2(x0, 10.0, 0.0)
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
