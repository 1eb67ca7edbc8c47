"""Tests of robot/vision/descriptors.py: OpenCV's methods through the front end."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robot.config import FeatureConfig, MatchConfig
from robot.vision.descriptors import _distinct
from robot.vision.front_end import FrontEnd, make_front_end
from shared.camera_model import CameraModel
from sim.synthetic.image_pairs import similarity_homography, transform_pixels, warped_pair

CAMERA = CameraModel.default()
#: Each method's descriptor: (dtype, length).
KINDS = {"orb": (np.uint8, 32), "teblid": (np.uint8, 32), "beblid": (np.uint8, 32),
         "akaze": (np.uint8, 61), "sift": (np.float32, 128)}


def _front_end(method: str, **changes: object) -> FrontEnd:
    return make_front_end(FeatureConfig(method=method, **changes), CAMERA)


def _pair(shift_xy: tuple[float, float], seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    H = similarity_homography(shift_xy)
    pair = warped_pair(np.random.default_rng(seed), H, CAMERA.width, CAMERA.height,
                       noise_sigma=2.0, gain=0.8, offset=20.0)
    return pair.image_a, pair.image_b, H


@pytest.mark.parametrize("method", sorted(KINDS))
def test_each_method_describes_inside_the_lens(method: str) -> None:
    image, _, _ = _pair((0.0, 0.0), seed=1)
    front_end = _front_end(method)
    feats = front_end.describe(image)
    dtype, length = KINDS[method]
    assert 50 <= len(feats) <= FeatureConfig().max_corners
    assert feats.descriptors.dtype == dtype and feats.descriptors.shape[1] == length
    assert feats.binary == (dtype == np.uint8)
    cols, rows = np.rint(feats.pixels_xy).astype(int).T
    assert front_end.mask[rows, cols].all()
    assert np.all(np.diff(feats.response) <= 0)


@pytest.mark.parametrize("method", ["orb", "teblid", "beblid"])
def test_shifted_view_matches_at_the_shift(method: str) -> None:
    image_a, image_b, H = _pair((6.0, -4.0), seed=2)
    front_end = _front_end(method)
    feats_a, feats_b = front_end.describe(image_a), front_end.describe(image_b)
    matches = front_end.match(feats_a, feats_b, MatchConfig())
    pixels_a, pixels_b = matches.pixels_xy(feats_a, feats_b)
    error_px = np.linalg.norm(transform_pixels(H, pixels_a) - pixels_b, axis=1)
    assert len(matches) >= 100
    assert np.mean(error_px <= 2.0) > 0.95
    # Sub-pixel corners: the shift is found to a fraction of a pixel.
    assert np.median(error_px) < 0.3


def test_corners_spread_over_the_image_where_harris_clusters() -> None:
    """A dim textured scene with one bright, contrasted patch (a lamp, a poster): the
    paper's relative Harris threshold keeps the patch's corners only, the FAST grid keeps
    corners everywhere."""
    image, _, _ = _pair((0.0, 0.0), seed=3)
    dim = (image.astype(np.float32) * 0.2 + 40).astype(np.uint8)
    dim[250:330, 360:440] = image[250:330, 360:440]  # full contrast, 80 x 80 px
    in_patch = {}
    for method in ("harris-zncc", "orb"):
        feats = _front_end(method).describe(dim)
        x, y = feats.pixels_xy.T
        in_patch[method] = np.mean((x > 350) & (x < 450) & (y > 240) & (y < 340))
    assert in_patch["harris-zncc"] > 0.8
    assert in_patch["orb"] < 0.2


def test_grid_cells_share_the_budget() -> None:
    image, _, _ = _pair((0.0, 0.0), seed=4)
    feats = _front_end("orb", grid_cells=4, max_corners=64).describe(image)
    side = 800 / 4
    cells = (feats.pixels_xy[:, 1] // side) * 4 + feats.pixels_xy[:, 0] // side
    assert len(feats) <= 64
    # At most ceil(64 / cells in the lens) per cell: none holds most of them.
    assert np.bincount(cells.astype(int)).max() <= 64 // 6 + 1


def test_hamming_threshold_comes_from_the_features_table() -> None:
    image_a, image_b, _ = _pair((3.0, 2.0), seed=5)
    loose = _front_end("orb")
    strict = make_front_end(dataclasses.replace(loose.config, max_hamming_fraction=0.02),
                            CAMERA)
    feats_a, feats_b = loose.describe(image_a), loose.describe(image_b)
    found = loose.match(feats_a, feats_b, MatchConfig())
    few = strict.match(feats_a, feats_b, MatchConfig())
    assert len(few) < len(found)
    assert np.all(few.score >= 1.0 - 2.0 * 0.02 - 1e-6)


def test_a_blank_image_gives_no_features() -> None:
    for method in KINDS:
        feats = _front_end(method).describe(np.full((600, 800), 90, np.uint8))
        assert len(feats) == 0
        assert feats.descriptors.shape[1] == KINDS[method][1]


def test_corners_within_a_pixel_of_a_stronger_one_are_dropped() -> None:
    """The refined FAST corners of one saddle collapse onto it: only the strongest (first)
    of those within 1 px stays, whatever lies between them in x (the sorted sweep agrees
    with comparing every pair)."""
    rng = np.random.default_rng(5)
    pixels = rng.uniform(0.0, 800.0, (300, 2))
    pixels[40] = pixels[7] + (0.3, -0.4)  # a weaker twin of corner 7
    pixels[3] = pixels[90] + (0.5, 0.5)  # a stronger twin of corner 90
    # a column 0.6 px apart: each is within 1 px of the one before it
    pixels[100:106] = (250.2, 10.0) + np.arange(6)[:, None] * (0.0, 0.6)
    kept = _distinct(pixels)
    pairs = np.hypot(*(pixels[:, None, :] - pixels[None, :, :]).transpose(2, 0, 1)) < 1.0
    assert (kept == ~np.tril(pairs, k=-1).any(axis=1)).all()
    assert kept[7] and not kept[40] and kept[3] and not kept[90]
    assert list(kept[100:106]) == [True, False, False, False, False, False]
    image, _, _ = _pair((0.0, 0.0), seed=4)
    found = _front_end("orb").describe(image).pixels_xy
    gaps = np.hypot(*(found[:, None, :] - found[None, :, :]).transpose(2, 0, 1))
    assert gaps[~np.eye(len(found), dtype=bool)].min() >= 1.0
