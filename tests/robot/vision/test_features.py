"""Tests of robot/vision/features.py: the Features record, Harris corners and ZNCC patches."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from robot.config import FeatureConfig
from robot.vision.features import (
    Features,
    Keypoints,
    PixelSizes,
    detect_harris,
    pixels_per_radian,
)
from shared.camera_model import CameraModel
from shared.errors import ShapeError
from sim.synthetic.image_pairs import texture

CONFIG = FeatureConfig()
P = PixelSizes.for_camera(CONFIG, CameraModel.default()).patch_px


def _textured(seed: int, width: int = 320, height: int = 240) -> np.ndarray:
    image = texture(np.random.default_rng(seed), width, height)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def _patch_pixels(image: np.ndarray, pixels_xy: np.ndarray, side: int) -> np.ndarray:
    """Reference: the raw (N, side*side) patches at rounded positions, by a plain loop."""
    half = side // 2
    out = []
    for x, y in np.rint(pixels_xy).astype(int):
        out.append(image[y - half:y + half + 1, x - half:x + half + 1].astype(np.float64).ravel())
    return np.array(out).reshape(-1, side * side)


def _assert_empty(feats: Features | Keypoints, side: int = P) -> None:
    assert len(feats) == 0
    assert feats.pixels_xy.shape == (0, 2)
    assert feats.descriptors.shape == (0, side * side)
    assert feats.response.shape == (0,)


class TestFeatures:
    def test_smoke(self) -> None:
        feats = Features(np.zeros((2, 2)), np.zeros((2, 9)), np.zeros(2), np.zeros((2, 3)))
        assert len(feats) == 2
        assert not feats.binary
        assert feats.pixels_xy.dtype == np.float64
        assert feats.descriptors.dtype == np.float32
        assert feats.response.dtype == np.float32
        assert feats.bearings.dtype == np.float64
        bits = Features(np.zeros((1, 2)), np.zeros((1, 32), np.uint8), np.zeros(1),
                        np.zeros((1, 3)))
        assert bits.binary

    def test_arrays_are_read_only(self) -> None:
        pixels = np.zeros((1, 2))
        feats = Features(pixels, np.zeros((1, 9)), np.zeros(1), np.zeros((1, 3)))
        with pytest.raises(ValueError, match="read-only"):
            feats.pixels_xy[0, 0] = 1.0
        pixels[0, 0] = 1.0  # the caller's array stays writeable

    @pytest.mark.parametrize(
        ("pixels", "descriptors", "response", "bearings", "name"),
        [
            ((2, 3), (2, 9), (2,), (2, 3), "pixels_xy"),
            ((2, 2), (3, 9), (2,), (2, 3), "descriptors"),
            ((2, 2), (2, 9), (3,), (2, 3), "response"),
            ((2, 2), (2, 9), (2,), (2, 2), "bearings"),
            ((2, 2), (2, 0), (2,), (2, 3), "descriptors: rows are empty"),
        ],
    )
    def test_shape_errors(self, pixels: tuple, descriptors: tuple, response: tuple,
                          bearings: tuple, name: str) -> None:
        with pytest.raises(ShapeError, match=name):
            Features(np.zeros(pixels), np.zeros(descriptors), np.zeros(response),
                     np.zeros(bearings))

    def test_descriptor_dtype(self) -> None:
        with pytest.raises(TypeError, match="descriptors: expected floats or uint8, got int64"):
            Features(np.zeros((1, 2)), np.zeros((1, 4), np.int64), np.zeros(1), np.zeros((1, 3)))

    def test_empty(self) -> None:
        _assert_empty(Features.empty(49), 7)
        assert Features.empty(32, np.uint8).binary

    def test_subset(self) -> None:
        feats = Features(np.arange(6.0).reshape(3, 2), np.eye(3), np.arange(3.0),
                         np.eye(3)[::-1])
        part = feats.subset(np.array([2, 0]))
        np.testing.assert_array_equal(part.pixels_xy, [[4, 5], [0, 1]])
        np.testing.assert_array_equal(part.descriptors, np.eye(3)[[2, 0]])
        np.testing.assert_array_equal(part.response, [2, 0])
        np.testing.assert_array_equal(part.bearings, np.eye(3)[::-1][[2, 0]])


class TestDetectHarris:
    def test_smoke(self) -> None:
        feats = detect_harris(_textured(0), CONFIG)
        assert 50 <= len(feats) <= CONFIG.max_corners
        assert feats.descriptors.shape == (len(feats), P * P)
        assert feats.descriptors.dtype == np.float32

    def test_shape_errors(self) -> None:
        with pytest.raises(ShapeError, match="image"):
            detect_harris(np.zeros((10, 10, 3), np.uint8), CONFIG)
        for shape in ((60, 80), (4, 4)):
            with pytest.raises(ShapeError, match="mask: expected shape"):
                detect_harris(np.zeros(shape, np.uint8), CONFIG, np.ones((60, 81), bool))

    def test_dtype_errors(self) -> None:
        with pytest.raises(TypeError, match="image: expected dtype uint8, got float64"):
            detect_harris(np.zeros((60, 80)), CONFIG)
        with pytest.raises(TypeError, match="mask: expected dtype bool, got uint8"):
            detect_harris(np.zeros((60, 80), np.uint8), CONFIG, np.ones((60, 80), np.uint8))

    def test_square_corners_known_answer(self) -> None:
        # A bright square covering pixels 40..79 x 30..69: its corners lie on the
        # pixel boundaries, at (39.5, 29.5), (79.5, 29.5), (39.5, 69.5), (79.5, 69.5).
        image = np.full((100, 120), 50, np.uint8)
        image[30:70, 40:80] = 200
        feats = detect_harris(image, CONFIG)
        expected = np.array([[39.5, 29.5], [79.5, 29.5], [39.5, 69.5], [79.5, 69.5]])
        assert len(feats) == 4
        dist = np.linalg.norm(feats.pixels_xy[:, None, :] - expected[None], axis=2)
        assert np.all(dist.min(axis=1) < 0.5)
        assert sorted(dist.argmin(axis=1)) == [0, 1, 2, 3]

    def test_patches_are_normalised_image_patches(self) -> None:
        image = _textured(1)
        feats = detect_harris(image, CONFIG)
        raw = _patch_pixels(image, feats.pixels_xy, P)
        centred = raw - raw.mean(axis=1, keepdims=True)
        expected = centred / np.linalg.norm(centred, axis=1, keepdims=True)
        np.testing.assert_allclose(feats.descriptors, expected, atol=1e-5)
        np.testing.assert_allclose(feats.descriptors.mean(axis=1), 0.0, atol=1e-6)
        np.testing.assert_allclose(np.linalg.norm(feats.descriptors, axis=1), 1.0, atol=1e-5)

    def test_strongest_first_and_capped(self) -> None:
        config = dataclasses.replace(CONFIG, max_corners=40)
        feats = detect_harris(_textured(2), config)
        assert len(feats) == 40
        assert np.all(np.diff(feats.response) <= 0)
        assert np.all(feats.response > 0)

    def test_min_distance(self) -> None:
        config = dataclasses.replace(CONFIG, subpixel_half_window_px=0)
        sizes = PixelSizes(patch_px=P, min_distance_px=15.0, descriptor_px=31)
        feats = detect_harris(_textured(3), config, None, sizes)
        dist = np.linalg.norm(feats.pixels_xy[:, None] - feats.pixels_xy[None], axis=2)
        np.fill_diagonal(dist, np.inf)
        assert dist.min() >= 15.0

    def test_no_patch_crosses_the_border(self) -> None:
        # Corners everywhere, including against the image border.
        rows, cols = np.indices((120, 160))
        image = ((rows // 4 + cols // 4) % 2 * 200 + 20).astype(np.uint8)
        feats = detect_harris(image, dataclasses.replace(CONFIG, max_corners=2000))
        half = P // 2
        centres = np.rint(feats.pixels_xy)
        assert len(feats) > 100
        assert centres[:, 0].min() >= half and centres[:, 0].max() <= 159 - half
        assert centres[:, 1].min() >= half and centres[:, 1].max() <= 119 - half

    def test_patches_stay_inside_the_mask(self) -> None:
        image = _textured(4)
        mask = np.zeros(image.shape, bool)
        cv2.circle(mask.view(np.uint8), (160, 120), 90, 1, -1)
        feats = detect_harris(image, CONFIG, mask)
        assert len(feats) > 20
        inside = _patch_pixels(mask.astype(np.uint8), feats.pixels_xy, P)
        assert np.all(inside == 1)

    def test_brightness_affine_invariance(self) -> None:
        # 2 I + 1 is exact in uint8 for I <= 127 and scales every gradient by exactly 2.
        image = (_textured(5) // 2).astype(np.uint8)
        brighter = (2 * image + 1).astype(np.uint8)
        feats, feats_bright = detect_harris(image, CONFIG), detect_harris(brighter, CONFIG)
        np.testing.assert_allclose(feats_bright.pixels_xy, feats.pixels_xy, atol=1e-3)
        np.testing.assert_allclose(feats_bright.descriptors, feats.descriptors, atol=1e-5)

    def test_strided_image(self) -> None:
        image = _textured(7, 640, 480)
        strided, copy = image[::2, ::2], np.ascontiguousarray(image[::2, ::2])
        np.testing.assert_array_equal(detect_harris(strided, CONFIG).descriptors,
                                      detect_harris(copy, CONFIG).descriptors)

    @pytest.mark.parametrize("shape", [(0, 0), (0, 50), (5, 5), (2 * (P // 2 + 3), 100)])
    def test_too_small_images_give_empty_features(self, shape: tuple[int, int]) -> None:
        _assert_empty(detect_harris(np.zeros(shape, np.uint8), CONFIG))

    def test_flat_image_gives_empty_features(self) -> None:
        _assert_empty(detect_harris(np.full((60, 80), 128, np.uint8), CONFIG))

    def test_empty_mask_gives_empty_features(self) -> None:
        _assert_empty(detect_harris(_textured(6), CONFIG, np.zeros((240, 320), bool)))


class TestPixelSizes:
    def test_default_lens_keeps_the_reference_sizes(self) -> None:
        camera = CameraModel.default()
        assert pixels_per_radian(camera) == pytest.approx(173.8, abs=0.1)
        sizes = PixelSizes.for_camera(FeatureConfig(), camera)
        assert (sizes.patch_px, sizes.descriptor_px) == (11, 31)
        assert sizes.min_distance_px == pytest.approx(8.0)

    def test_a_sharper_lens_gets_wider_windows(self) -> None:
        # The MYNT EYE's 366 px/rad: the same angles span twice the pixels.
        sizes = PixelSizes.for_lens(FeatureConfig(), 366.0)
        assert (sizes.patch_px, sizes.descriptor_px) == (23, 65)
        assert sizes.patch_px % 2 == 1

    def test_smallest_sizes(self) -> None:
        sizes = PixelSizes.for_lens(FeatureConfig(), 1.0)
        assert (sizes.patch_px, sizes.descriptor_px) == (3, 7)

    def test_harris_patches_follow_the_sizes(self) -> None:
        sizes = PixelSizes(patch_px=7, min_distance_px=8.0, descriptor_px=31)
        feats = detect_harris(_textured(8), CONFIG, None, sizes)
        assert feats.descriptors.shape == (len(feats), 49)
