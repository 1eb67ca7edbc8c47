"""Tests of sim/synthetic/corridor_scene.py: the corridor generator's ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.camera_mount import camera_pose_world
from sim.synthetic.corridor_scene import compose, corridor_scene


class TestCorridorScene:
    def test_truth_is_consistent(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng)
        assert compose(s.next.pose_w, (s.s_m, s.y_m, s.theta_rad)) == pytest.approx(
            s.current.pose_w)
        assert abs(s.y_m) <= 0.5 and abs(math.degrees(s.theta_rad)) <= 20.0
        assert s.previous.pose_w[0] <= s.current.pose_w[0] + 0.5

    def test_pixels_are_noisy_projections(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng, noise_px=1.0)
        T = camera_pose_world(s.current.pose_w, s.mount)
        exact, valid = s.camera.project((s.points_w[s.current.point_ids] - T[:3, 3]) @ T[:3, :3])
        assert valid.all()
        residual = s.current.pixels_xy - exact
        assert np.std(residual) == pytest.approx(1.0, rel=0.2)

    def test_matches_and_outliers(self, rng: np.random.Generator) -> None:
        s = corridor_scene(rng, outlier_ratio=0.2)
        m = s.current_next
        same = s.current.point_ids[m.idx_view] == s.next.point_ids[m.idx_next]
        np.testing.assert_array_equal(same, ~m.outlier)
        assert 0.1 < m.outlier.mean() < 0.3 and len(m.outlier) > 100

    def test_rays_beyond_90_degrees_are_matched(self, rng: np.random.Generator) -> None:
        # A 185 degree lens sees only 2.5 degrees past the image plane: a few per corridor.
        behind = 0
        for _ in range(5):
            s = corridor_scene(rng)
            T = camera_pose_world(s.next.pose_w, s.mount)
            ids = s.next.point_ids[s.current_next.idx_next]
            behind += int(np.count_nonzero(((s.points_w[ids] - T[:3, 3]) @ T[:3, :3])[:, 2] < 0))
        assert behind >= 5
