"""Tests of shared/kannala_brandt.py: the equidistant model and the unified fit to it."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from shared.errors import CalibrationError, ShapeError
from shared.kannala_brandt import DISTORTION_ABOVE_PX, KannalaBrandtCamera, fit_unified
from shared.kannala_brandt_yaml import read_equidistant_yaml
from tools.bench.realdata import FISHEYE_LEFT_YAML

#: The MYNT EYE left camera of the vendored fisheye pair.
MYNT = read_equidistant_yaml(FISHEYE_LEFT_YAML).camera


def image_pixels(kb: KannalaBrandtCamera, step: float) -> np.ndarray:
    u, v = np.meshgrid(np.arange(0.0, kb.width, step), np.arange(0.0, kb.height, step))
    return np.stack([u.ravel(), v.ravel()], axis=1)


class TestKannalaBrandtCamera:
    def test_projects_as_cv2_fisheye(self, rng: np.random.Generator) -> None:
        bearings = rng.normal(size=(500, 3))
        bearings[:, 2] = np.abs(bearings[:, 2]) + 0.3  # in front: cv2.fisheye's domain
        pixels, valid = MYNT.project(bearings)
        K = np.array([[MYNT.fx, 0, MYNT.cx], [0, MYNT.fy, MYNT.cy], [0, 0, 1]])
        expected, _ = cv2.fisheye.projectPoints(bearings.reshape(-1, 1, 3), np.zeros(3),
                                                np.zeros(3), K, MYNT.k)
        assert valid.all()
        assert np.abs(pixels - expected.reshape(-1, 2)).max() < 1e-9

    def test_lift_inverts_project(self) -> None:
        pixels = image_pixels(MYNT, 7.0)
        bearings, valid = MYNT.lift(pixels)
        assert valid.all()
        assert np.allclose(np.linalg.norm(bearings, axis=1), 1.0)
        back, ok = MYNT.project(bearings)
        assert ok.all() and np.abs(back - pixels).max() < 1e-9

    def test_beyond_the_one_to_one_range_is_invalid(self) -> None:
        # theta_d of the MYNT lens peaks near 98 degrees: a pixel further out has no ray.
        assert 1.6 < MYNT.theta_max_rad < 1.8
        far = np.array([[MYNT.cx + 1.6 * MYNT.fx, MYNT.cy]])
        assert not MYNT.lift(far)[1][0]

    def test_shapes(self) -> None:
        with pytest.raises(ShapeError):
            MYNT.lift(np.zeros((3, 3)))
        with pytest.raises(ShapeError):
            MYNT.project(np.zeros((3, 2)))
        with pytest.raises(ShapeError):
            KannalaBrandtCamera(10, 10, 1.0, 1.0, 5.0, 5.0, np.zeros(3))


class TestFitUnified:
    def test_mynt_lens(self) -> None:
        fit = fit_unified(MYNT, "left.yaml")
        camera = fit.camera
        # Principal point and aspect ratio are kept exactly; no distortion is needed.
        assert (camera.K[0, 2], camera.K[1, 2]) == (MYNT.cx, MYNT.cy)
        assert camera.K[0, 0] / camera.K[1, 1] == pytest.approx(MYNT.fx / MYNT.fy, rel=1e-12)
        assert not fit.with_distortion and not camera.has_distortion
        # An equidistant lens is xi ~ 2 in the unified model (module docstring).
        assert 2.0 < camera.xi < 3.0
        assert fit.rms_px < 0.06 and fit.max_px < 0.2
        assert camera.fov_deg == 152.0
        # The stated residual holds on every pixel, not only on the fit's grid.
        pixels = image_pixels(MYNT, 3.0)
        projected, ok = camera.project(MYNT.lift(pixels)[0])
        err = np.linalg.norm(projected - pixels, axis=1)
        assert ok.all() and err.max() < fit.max_px + 0.01
        assert math.sqrt(np.mean(err**2)) == pytest.approx(fit.rms_px, abs=0.01)

    def test_fits_distortion_when_xi_alone_misses(self) -> None:
        # A 189-degree lens whose profile xi alone cannot follow.
        kb = KannalaBrandtCamera(640, 480, 250.0, 250.0, 320.0, 240.0, [-0.01, 0.0, 0.0, 0.0])
        fit = fit_unified(kb, "wide.yaml")
        assert fit.with_distortion and fit.max_px < DISTORTION_ABOVE_PX
        assert fit.camera.fov_deg > 185.0

    def test_a_lens_the_unified_model_cannot_follow(self) -> None:
        kb = KannalaBrandtCamera(1280, 800, 300.0, 300.0, 640.0, 400.0, [0.08, -0.05, 0.01, 0.0])
        with pytest.raises(CalibrationError, match=r"wild\.yaml: the unified model fitted"):
            fit_unified(kb, "wild.yaml")

    def test_image_beyond_the_equidistant_range(self) -> None:
        kb = KannalaBrandtCamera(752, 480, 100.0, 100.0, 376.0, 240.0, [-0.05, 0.0, 0.0, 0.0])
        with pytest.raises(CalibrationError, match="lies beyond the equidistant model's"):
            fit_unified(kb, "small.yaml")
