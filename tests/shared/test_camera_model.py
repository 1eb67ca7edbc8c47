"""Tests of shared/camera_model.py: the unified sphere model, both directions."""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.camera_model import CameraModel
from shared.errors import ShapeError

#: A realistic calibrated fisheye (what cv2.omnidir.calibrate finds for the
#: default lens), with a little skew so every term of the model is exercised.
DISTORTED = CameraModel(
    width=800,
    height=600,
    K=np.array([[378.8, 0.4, 399.2], [0.0, 378.6, 299.9], [0.0, 0.0, 1.0]]),
    xi=1.18,
    D=np.array([-0.21, 0.03, 0.0008, -0.0004]),
    fov_deg=185.0,
)
CAMERAS = {"default": CameraModel.default(), "distorted": DISTORTED}


def ray(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    """(1, 3) unit bearing ``theta_deg`` off the optical axis at azimuth ``phi_deg``."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([[math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]])


def all_pixel_centres(camera: CameraModel) -> np.ndarray:
    """(W * H, 2) every pixel centre of the image."""
    u, v = np.meshgrid(np.arange(camera.width, dtype=float), np.arange(camera.height, dtype=float))
    return np.stack([u.ravel(), v.ravel()], axis=1)


def off_axis_deg(bearings: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(bearings[:, 2], -1.0, 1.0)))


class TestConstruction:
    def test_default_camera(self) -> None:
        cam = CameraModel.default()
        assert (cam.width, cam.height, cam.xi, cam.fov_deg) == (800, 600, 1.6, 185.0)
        assert not cam.has_distortion
        assert cam.min_z_s == pytest.approx(math.cos(math.radians(92.5)))
        # The 92.5 degree ray lands 290 px from the principal point (399.5, 299.5).
        pixels, _ = cam.project(ray(92.5))
        np.testing.assert_allclose(pixels, [[399.5 + 290.0, 299.5]], atol=1e-9)

    def test_accepts_omnidir_output_shapes(self) -> None:
        # cv2.omnidir.calibrate returns xi as a (1, 1) array and D as (1, 4).
        cam = CameraModel(800, 600, np.eye(3), np.array([[1.25]]), np.array([[0.1, 0.2, 0.3, 0.4]]))
        assert cam.xi == 1.25 and isinstance(cam.xi, float)
        np.testing.assert_array_equal(cam.D, [0.1, 0.2, 0.3, 0.4])
        assert cam.has_distortion

    @pytest.mark.parametrize(
        ("K", "xi", "D"),
        [
            (np.eye(2), 1.0, np.zeros(4)),
            (np.eye(3), [1.0, 2.0], np.zeros(4)),
            (np.eye(3), 1.0, np.zeros(5)),
        ],
    )
    def test_shape_errors(self, K: np.ndarray, xi: object, D: np.ndarray) -> None:
        with pytest.raises(ShapeError):
            CameraModel(800, 600, K, xi, D)

    def test_arrays_are_read_only(self) -> None:
        cam = CameraModel.default()
        with pytest.raises(ValueError, match="read-only"):
            cam.K[0, 0] = 1.0

    def test_min_z_s_for_xi_above_one_limits_the_fov(self) -> None:
        # xi = 2: the model folds over at z_s = -1/2 (120 degrees), inside a 300 degree FOV.
        cam = CameraModel(800, 600, np.eye(3), 2.0, fov_deg=300.0)
        assert cam.min_z_s == pytest.approx(-0.5)


class TestProject:
    def test_smoke(self) -> None:
        pixels, valid = CameraModel.default().project(np.array([[0.0, 0.0, 1.0], [0.1, -0.2, 1.0]]))
        assert pixels.shape == (2, 2) and pixels.dtype == np.float64
        assert valid.shape == (2,) and valid.dtype == np.bool_ and valid.all()

    def test_empty_input(self) -> None:
        pixels, valid = CameraModel.default().project(np.zeros((0, 3)))
        assert pixels.shape == (0, 2) and valid.shape == (0,)

    @pytest.mark.parametrize("shape", [(3,), (4, 2), (2, 4), (1, 3, 1)])
    def test_shape_errors(self, shape: tuple[int, ...]) -> None:
        with pytest.raises(ShapeError, match="points_c"):
            CameraModel.default().project(np.ones(shape))

    def test_optical_axis_hits_principal_point(self) -> None:
        for cam in CAMERAS.values():
            pixels, valid = cam.project(np.array([[0.0, 0.0, 3.0]]))
            np.testing.assert_allclose(pixels[0], cam.K[:2, 2], atol=1e-12)
            assert valid[0]

    @pytest.mark.parametrize("theta_deg", [10.0, 45.0, 90.0, 92.0])
    def test_known_radius_without_distortion(self, theta_deg: float) -> None:
        # Mei & Rives eq. 3 along +y: v - cy = f sin(theta) / (cos(theta) + xi).
        cam = CameraModel.default()
        t = math.radians(theta_deg)
        pixels, valid = cam.project(ray(theta_deg, 90.0))
        expected = cam.K[1, 1] * math.sin(t) / (math.cos(t) + cam.xi)
        np.testing.assert_allclose(pixels[0], [399.5, 299.5 + expected], atol=1e-9)
        assert valid[0]

    def test_known_answer_with_distortion_and_skew(self) -> None:
        # The point with normalised coordinates m = (0.3, -0.2), distorted by hand.
        cam = DISTORTED
        mx, my = 0.3, -0.2
        # Bearing whose sphere lift gives m: X_s = (lam mx, lam my, lam - xi).
        r2 = mx * mx + my * my
        lam = (cam.xi + math.sqrt(1 + (1 - cam.xi**2) * r2)) / (r2 + 1)
        k1, k2, p1, p2 = cam.D
        radial = 1 + k1 * r2 + k2 * r2 * r2
        dx = mx * radial + 2 * p1 * mx * my + p2 * (r2 + 2 * mx * mx)
        dy = my * radial + p1 * (r2 + 2 * my * my) + 2 * p2 * mx * my
        (fx, s, cx), (_, fy, cy) = cam.K[0], cam.K[1]
        pixels, valid = cam.project(np.array([[lam * mx, lam * my, lam - cam.xi]]))
        np.testing.assert_allclose(pixels[0], [fx * dx + s * dy + cx, fy * dy + cy], atol=1e-9)
        assert valid[0]

    def test_scale_does_not_matter(self, rng: np.random.Generator) -> None:
        points = rng.normal(size=(50, 3)) + np.array([0.0, 0.0, 2.0])
        a, va = DISTORTED.project(points)
        b, vb = DISTORTED.project(points * rng.uniform(0.01, 100.0, size=(50, 1)))
        np.testing.assert_allclose(a, b, atol=1e-9)
        np.testing.assert_array_equal(va, vb)

    @pytest.mark.parametrize("name", ["default", "distorted"])
    def test_agrees_with_opencv_below_90_degrees(self, name: str, rng: np.random.Generator) -> None:
        cam = CAMERAS[name]
        theta = np.radians(rng.uniform(0.0, 89.9, 2000))
        phi = rng.uniform(0.0, 2 * np.pi, 2000)
        points = np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1
        )
        points *= rng.uniform(0.5, 20.0, (2000, 1))
        ours, _ = cam.project(points)
        theirs, _ = cv2.omnidir.projectPoints(
            points.reshape(-1, 1, 3),
            np.zeros(3),
            np.zeros(3),
            cam.K,
            float(cam.xi),
            cam.D.reshape(1, 4),
        )
        np.testing.assert_allclose(ours, theirs.reshape(-1, 2), atol=1e-6)

    def test_validity_at_the_fov_limit(self) -> None:
        cam = CameraModel.default()
        for phi in (0.0, 90.0, 200.0):
            assert cam.project(ray(92.0, phi))[1][0]
            assert not cam.project(ray(93.0, phi))[1][0]
        assert not cam.project(ray(180.0))[1][0]

    def test_zero_vector_is_invalid(self) -> None:
        _, valid = CameraModel.default().project(np.zeros((1, 3)))
        assert not valid[0]

    def test_pixel_outside_image_is_invalid(self) -> None:
        # A 100 x 100 crop of the default lens: a 60 degree ray lands outside it.
        base = CameraModel.default()
        K = base.K.copy()
        K[:2, 2] = 49.5
        cam = CameraModel(100, 100, K, base.xi)
        pixels, valid = cam.project(np.concatenate([ray(5.0), ray(60.0)]))
        assert valid[0]
        assert not valid[1] and pixels[1, 0] > 99.5


class TestLift:
    def test_smoke(self) -> None:
        bearings, valid = CameraModel.default().lift(np.array([[399.5, 299.5], [200.0, 250.0]]))
        assert bearings.shape == (2, 3) and bearings.dtype == np.float64
        assert valid.shape == (2,) and valid.all()
        np.testing.assert_allclose(np.linalg.norm(bearings, axis=1), 1.0, atol=1e-12)

    @pytest.mark.parametrize("shape", [(2,), (4, 3), (3, 1), (1, 2, 1)])
    def test_shape_errors(self, shape: tuple[int, ...]) -> None:
        with pytest.raises(ShapeError, match="pixels_xy"):
            CameraModel.default().lift(np.ones(shape))

    def test_principal_point_is_the_optical_axis(self) -> None:
        for cam in CAMERAS.values():
            bearings, valid = cam.lift(cam.K[:2, 2].reshape(1, 2))
            np.testing.assert_allclose(bearings[0], [0.0, 0.0, 1.0], atol=1e-12)
            assert valid[0]

    def test_known_answer_beyond_90_degrees(self) -> None:
        # Default camera: 285 px right of centre is a ray off-axis by theta with
        # f sin(theta) / (cos(theta) + xi) = 285, which is beyond 90 degrees.
        cam = CameraModel.default()
        f = cam.K[0, 0]
        theta = _solve_theta(lambda t: f * math.sin(t) / (math.cos(t) + cam.xi) - 285.0)
        assert 90.0 < math.degrees(theta) < 92.5
        bearings, valid = cam.lift(np.array([[399.5 + 285.0, 299.5]]))
        np.testing.assert_allclose(bearings[0], [math.sin(theta), 0.0, math.cos(theta)], atol=1e-12)
        assert valid[0]

    def test_corners_of_the_default_image_are_invalid(self) -> None:
        corners = np.array([[0.0, 0.0], [799.0, 0.0], [0.0, 599.0], [799.0, 599.0]])
        _, valid = CameraModel.default().lift(corners)
        assert not valid.any()

    def test_pixel_outside_image_is_invalid(self) -> None:
        outside = np.array([[-0.6, 300.0], [799.6, 300.0], [400.0, -0.6], [400.0, 599.6]])
        for cam in CAMERAS.values():
            _, valid = cam.lift(outside)
            assert not valid.any()

    @pytest.mark.parametrize("name", ["default", "distorted"])
    def test_round_trip_over_the_whole_image(self, name: str) -> None:
        cam = CAMERAS[name]
        pixels = all_pixel_centres(cam)
        bearings, valid = cam.lift(pixels)
        # Everything within the 92.5 degree image circle is valid, the rest not.
        angle = off_axis_deg(bearings[valid])
        assert angle.max() < 92.5
        outside = ~valid & np.isfinite(bearings).all(axis=1)
        assert off_axis_deg(bearings[outside]).min() >= 92.5
        back, back_valid = cam.project(bearings[valid])
        assert back_valid.all()
        err = np.linalg.norm(back - pixels[valid], axis=1)
        assert err.max() < 1e-6
        # Rays between 90 and 92.5 degrees: beyond the image plane, still exact.
        behind = angle > 90.0
        assert behind.sum() > 1000
        assert err[behind].max() < 1e-6
        np.testing.assert_allclose(np.linalg.norm(bearings[valid], axis=1), 1.0, atol=1e-12)

    @pytest.mark.parametrize("name", ["default", "distorted"])
    def test_bearing_round_trip(self, name: str, rng: np.random.Generator) -> None:
        cam = CAMERAS[name]
        theta = np.radians(rng.uniform(0.0, 92.4, 5000))
        phi = rng.uniform(0.0, 2 * np.pi, 5000)
        bearings = np.stack(
            [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1
        )
        pixels, valid = cam.project(bearings)
        assert valid.all()
        back, back_valid = cam.lift(pixels)
        assert back_valid.all()
        np.testing.assert_allclose(back, bearings, atol=1e-10)

    def test_lift_beyond_the_image_circle_is_invalid(self) -> None:
        # 300 px right of centre: the 92.5 degree limit is at 290 px.
        _, valid = CameraModel.default().lift(np.array([[399.5, 299.5 + 295.0]]))
        assert not valid[0]


@settings(max_examples=300, deadline=None)
@given(
    u=st.floats(0.0, 799.0),
    v=st.floats(0.0, 599.0),
    name=st.sampled_from(sorted(CAMERAS)),
)
def test_round_trip_property(u: float, v: float, name: str) -> None:
    cam = CAMERAS[name]
    bearings, valid = cam.lift(np.array([[u, v]]))
    if valid[0]:
        back, back_valid = cam.project(bearings)
        assert back_valid[0]
        assert np.linalg.norm(back[0] - [u, v]) < 1e-6
        assert abs(np.linalg.norm(bearings[0]) - 1.0) < 1e-12


def _solve_theta(f: Callable[[float], float]) -> float:
    """Root of the increasing ``f`` in (80, 100) degrees, by bisection."""
    lo, hi = math.radians(80.0), math.radians(100.0)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)
