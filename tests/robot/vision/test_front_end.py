"""Tests of robot/vision/front_end.py: one entry point for describing and matching images."""

from __future__ import annotations

import numpy as np
import pytest

from robot.config import FeatureConfig, MatchConfig
from robot.vision.front_end import (
    FrontEnd,
    check_front_end,
    front_end_label,
    make_front_end,
    stored_descriptors,
)
from shared.camera_model import CameraModel
from shared.errors import MemoryFormatError, ShapeError
from shared.memory import KeyframeRecord, VisualMemory
from sim.synthetic.image_pairs import texture

CAMERA = CameraModel.default()


@pytest.fixture(scope="module")
def front_end() -> FrontEnd:
    """The paper's method (float patches); the default's bit strings are tested apart."""
    return make_front_end(FeatureConfig(method="harris-zncc"), CAMERA)


def _textured(seed: int) -> np.ndarray:
    image = texture(np.random.default_rng(seed), CAMERA.width, CAMERA.height)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


def _rotation_y(angle_rad: float) -> np.ndarray:
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


class TestDescribe:
    def test_points_inside_the_lens_with_their_bearings(self, front_end: FrontEnd) -> None:
        feats = front_end.describe(_textured(0))
        assert front_end.method == "harris-zncc"
        assert 100 <= len(feats) <= FeatureConfig().max_corners
        cols, rows = np.rint(feats.pixels_xy).astype(int).T
        assert front_end.mask[rows, cols].all()
        bearings, valid = CAMERA.lift(feats.pixels_xy)
        assert valid.all()
        np.testing.assert_allclose(feats.bearings, bearings)
        np.testing.assert_allclose(np.linalg.norm(feats.bearings, axis=1), 1.0)

    def test_own_mask(self, front_end: FrontEnd) -> None:
        left = np.zeros((CAMERA.height, CAMERA.width), bool)
        left[:, :400] = front_end.mask[:, :400]
        feats = front_end.describe(_textured(1), left)
        assert len(feats) > 20 and feats.pixels_xy[:, 0].max() < 400

    def test_image_of_another_size(self, front_end: FrontEnd) -> None:
        with pytest.raises(ShapeError, match=r"image: expected shape \(600, 800\), got \(60, 80\)"):
            front_end.describe(np.zeros((60, 80), np.uint8))


class TestStoredFeatures:
    def test_round_trip(self, front_end: FrontEnd) -> None:
        feats = front_end.describe(_textured(2))
        stored = stored_descriptors(feats)
        assert stored.dtype == np.float32
        back = front_end.features(feats.pixels_xy, front_end.descriptors_from_stored(stored))
        np.testing.assert_array_equal(back.descriptors, feats.descriptors)
        np.testing.assert_allclose(back.bearings, feats.bearings)
        assert not back.response.any()

    def test_pixels_without_a_ray_look_forward(self, front_end: FrontEnd) -> None:
        feats = front_end.features(np.array([[0.0, 0.0], [399.5, 299.5]]), np.ones((2, 9)))
        np.testing.assert_allclose(feats.bearings, [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]], atol=1e-12)


class TestMatch:
    def test_guided_by_a_predicted_rotation(self, front_end: FrontEnd) -> None:
        """B sees A's points turned 30 degrees about the vertical: a 5 degree cone around
        A's own bearings misses them, around the predicted ones finds them all."""
        feats_a = front_end.describe(_textured(3))
        R_b_a = _rotation_y(np.radians(30.0))
        moved, valid = CAMERA.project(feats_a.bearings @ R_b_a.T)
        feats_b = front_end.features(moved[valid], feats_a.descriptors[valid])
        matching = MatchConfig(search_radius_deg=5.0)
        assert len(front_end.match(feats_a, feats_b, matching)) < 0.2 * len(feats_b)
        guided = front_end.match(feats_a, feats_b, matching, predicted=R_b_a)
        assert len(guided) == len(feats_b)
        np.testing.assert_array_equal(guided.idx_a, np.flatnonzero(valid))
        np.testing.assert_array_equal(guided.idx_b, np.arange(len(feats_b)))

    def test_predicted_must_be_a_matrix(self, front_end: FrontEnd) -> None:
        feats = front_end.describe(_textured(4))
        with pytest.raises(ShapeError, match="R_b_a: expected shape"):
            front_end.match(feats, feats, MatchConfig(), predicted=np.eye(2))


class TestDefault:
    def test_the_default_method_round_trips_through_a_memory(self) -> None:
        front_end = make_front_end(FeatureConfig(), CAMERA)
        feats = front_end.describe(_textured(5))
        assert front_end.method == "orb" and feats.binary
        assert feats.descriptors.shape[1] == front_end.descriptor_length == 32
        stored = stored_descriptors(feats)
        assert stored.dtype == np.float32 and stored.max() <= 255
        np.testing.assert_array_equal(front_end.descriptors_from_stored(stored),
                                      feats.descriptors)

    def test_a_memory_of_another_method_is_refused(self, front_end: FrontEnd) -> None:
        memory = VisualMemory(CAMERA)
        feats = front_end.describe(_textured(6))
        memory.add_path("p", [KeyframeRecord(t_ns=0, odom_pose=(0.0, 0.0, 0.0), distance_m=0.0,
                                             image=_textured(6), pixels_xy=feats.pixels_xy,
                                             patches=stored_descriptors(feats))])
        orb = make_front_end(FeatureConfig(), CAMERA)
        with pytest.raises(MemoryFormatError, match=r"key image 0: descriptors have 121 values, "
                                                    r"the front end 'orb' on this lens makes 32"):
            orb.features_from_keyframe(memory.keyframe(0))

    def test_a_memory_of_another_bit_string_method_is_refused(self) -> None:
        """ORB and TEBLID both make 32 bytes: only the label the memory records tells them
        apart, and the follower and the localizer refuse the memory before matching."""
        from robot.config import VmnavConfig
        from robot.memory.localize import Localizer

        orb = make_front_end(FeatureConfig(), CAMERA)
        teblid_config = FeatureConfig(method="teblid")
        label = front_end_label(FeatureConfig(), CAMERA)
        assert label == "orb, 31 px window"
        assert front_end_label(teblid_config, CAMERA) == "teblid, 31 px window"
        image = _textured(7)
        feats = orb.describe(image)
        memory = VisualMemory(CAMERA)
        memory.add_path("p", [KeyframeRecord(t_ns=0, odom_pose=(0.0, 0.0, 0.0), distance_m=0.0,
                                             image=image, pixels_xy=feats.pixels_xy,
                                             patches=stored_descriptors(feats))], label)
        check_front_end(memory, FeatureConfig())
        config = VmnavConfig()
        Localizer.from_memory(memory, config.camera.mount, config.features, config.localize)
        with pytest.raises(MemoryFormatError, match=r"visual memory: its key images were "
                           r"described by front end 'orb, 31 px window', the config's \[features\]"
                           r" makes 'teblid, 31 px window': set \[features\] method = 'orb'"):
            Localizer.from_memory(memory, config.camera.mount, teblid_config, config.localize)
