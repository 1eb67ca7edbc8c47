from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from shared.errors import MemoryFormatError, ShapeError
from shared.memory import Junction, Keyframe, VisualPath, thumbnail_from_image
from tests.shared.memory.builders import PATCH_LENGTH


def keyframe_fields(rng: np.random.Generator) -> dict[str, Any]:
    image = rng.integers(0, 256, size=(120, 160), dtype=np.uint8)
    patches = rng.standard_normal((5, PATCH_LENGTH)).astype(np.float32)
    return {
        "id": 7,
        "path_id": 1,
        "index": 2,
        "t_ns": 1_500_000_000,
        "odom_pose": (1.0, 0.5, 0.1),
        "distance_m": 1.25,
        "image": image,
        "pixels_xy": rng.uniform([0, 0], [159, 119], size=(5, 2)),
        "patches": patches,
        "thumbnail": thumbnail_from_image(image),
    }


class TestThumbnail:
    def test_block_means_known_answer(self) -> None:
        # 800x600 -> 80x60 is a 10x10 box average: a checkerboard of 10 px squares survives.
        blocks = (np.indices((60, 80)).sum(axis=0) % 2 * 200 + 20).astype(np.uint8)
        image = np.kron(blocks, np.ones((10, 10), dtype=np.uint8))
        thumb = thumbnail_from_image(image)
        assert thumb.shape == (60, 80) and thumb.dtype == np.uint8
        np.testing.assert_array_equal(thumb, blocks)

    def test_any_size(self, rng: np.random.Generator) -> None:
        image = rng.integers(0, 256, (37, 51), dtype=np.uint8)
        assert thumbnail_from_image(image).shape == (60, 80)

    @pytest.mark.parametrize(
        "image",
        [
            np.zeros((0, 0), np.uint8),
            np.zeros((60, 80, 3), np.uint8),
            np.zeros((60, 80), np.float32),
        ],
    )
    def test_refuses_non_grey(self, image: np.ndarray) -> None:
        with pytest.raises(ShapeError, match="image: expected a non-empty"):
            thumbnail_from_image(image)


class TestKeyframe:
    def test_keeps_values_and_owns_read_only_copies(self, rng: np.random.Generator) -> None:
        fields = keyframe_fields(rng)
        keyframe = Keyframe(**fields)
        assert (keyframe.id, keyframe.path_id, keyframe.index) == (7, 1, 2)
        assert keyframe.odom_pose == (1.0, 0.5, 0.1) and keyframe.n_features == 5
        assert keyframe.descriptor_length == PATCH_LENGTH
        np.testing.assert_array_equal(keyframe.image, fields["image"])
        fields["image"][0, 0] ^= 0xFF
        assert keyframe.image[0, 0] != fields["image"][0, 0]
        with pytest.raises(ValueError, match="read-only"):
            keyframe.patches[0, 0] = 1.0

    def test_tracks_default_to_none_and_are_kept_read_only(
        self, rng: np.random.Generator
    ) -> None:
        assert Keyframe(**keyframe_fields(rng)).tracked_from_previous.shape == (0, 2)
        tracks = np.array([[7, 0], [2, 4]])
        keyframe = Keyframe(**keyframe_fields(rng), tracked_from_previous=tracks)
        np.testing.assert_array_equal(keyframe.tracked_from_previous, tracks)
        with pytest.raises(ValueError, match="read-only"):
            keyframe.tracked_from_previous[0, 0] = 1

    def test_numpy_integers_become_ints(self, rng: np.random.Generator) -> None:
        keyframe = Keyframe(**{**keyframe_fields(rng), "id": np.int64(3), "t_ns": np.int64(9)})
        assert type(keyframe.id) is int and type(keyframe.t_ns) is int

    def test_no_features_is_allowed(self, rng: np.random.Generator) -> None:
        fields = keyframe_fields(rng)
        fields["pixels_xy"] = np.zeros((0, 2))
        fields["patches"] = np.zeros((0, PATCH_LENGTH), np.float32)
        assert Keyframe(**fields).n_features == 0

    @pytest.mark.parametrize(
        ("field", "value", "fragment"),
        [
            ("id", -1, "id: expected an integer >= 0"),
            ("index", True, "index: expected an integer >= 0"),
            ("t_ns", 1.5, "t_ns: expected an integer"),
            ("odom_pose", (1.0, 2.0), r"odom_pose: expected \(x_m, y_m, yaw_rad\)"),
            ("odom_pose", (1.0, float("nan"), 0.0), "odom_pose: expected a finite number"),
            ("distance_m", -0.1, "distance_m: must be >= 0 m"),
            ("distance_m", "1", "distance_m: expected a finite number"),
            ("image", np.zeros((120, 160), np.float32), "image: expected dtype uint8, got float32"),
            ("image", np.zeros((120, 160, 3), np.uint8), r"image: expected shape \(N, N\)"),
            ("image", np.zeros((0, 160), np.uint8), "image: empty image"),
            ("image", [[1, 2]], "image: expected a numpy array, got list"),
            ("pixels_xy", np.zeros((5, 3)), r"pixels_xy: expected shape \(N, 2\), got \(5, 3\)"),
            ("pixels_xy", np.zeros((4, 2)), "4 corners in pixels_xy but 5 rows in patches"),
            ("pixels_xy", np.full((5, 2), 200.0), "5 corners lie outside the 160x120 image"),
            ("patches", np.zeros((5, PATCH_LENGTH)), "patches: expected dtype float32, got f"),
            ("patches", np.zeros((5, 0), np.float32), "patches: descriptors are empty"),
            ("patches", np.full((5, PATCH_LENGTH), np.inf, np.float32), "patches: holds NaN"),
            ("thumbnail", np.zeros((60, 81), np.uint8), "thumbnail: expected 80x60 px, got 81x60"),
            ("tracked_from_previous", np.zeros((2, 3), np.int64),
             r"tracked_from_previous: expected shape \(N, 2\), got \(2, 3\)"),
            ("tracked_from_previous", np.zeros((1, 2), np.int32),
             "tracked_from_previous: expected dtype int64, got int32"),
            ("tracked_from_previous", np.array([[-1, 0]]), "holds a negative corner index"),
            ("tracked_from_previous", np.array([[0, 5]]),
             "corner 5 of this key image, which has 5"),
            ("tracked_from_previous", np.array([[0, 1], [0, 2]]),
             "repeats a corner of the previous key image's"),
            ("tracked_from_previous", np.array([[0, 1], [3, 1]]),
             "repeats a corner of this key image's"),
        ],
    )
    def test_bad_field_names_the_key_image_and_field(
        self, rng: np.random.Generator, field: str, value: Any, fragment: str
    ) -> None:
        fields = {**keyframe_fields(rng), field: value}
        with pytest.raises(MemoryFormatError, match=fragment) as error:
            Keyframe(**fields)
        assert error.value.where.startswith("key image")


class TestVisualPath:
    def test_list_becomes_tuple(self) -> None:
        assert VisualPath(id=0, name="corridor", keyframe_ids=[3, 4]).keyframe_ids == (3, 4)

    @pytest.mark.parametrize(
        ("fields", "fragment"),
        [
            ({"keyframe_ids": ()}, "keyframe_ids: expected at least one id"),
            ({"keyframe_ids": (1, 2, 1)}, "key image 1 appears twice"),
            ({"keyframe_ids": (1, -2)}, "keyframe_ids: expected an integer >= 0"),
            ({"name": " "}, "name: expected a non-empty line"),
            ({"name": "a\nb"}, "name: expected a non-empty line"),
            ({"id": "0"}, "id: expected an integer >= 0"),
        ],
    )
    def test_bad_fields(self, fields: dict[str, Any], fragment: str) -> None:
        with pytest.raises(MemoryFormatError, match=fragment):
            VisualPath(**{"id": 0, "name": "corridor", "keyframe_ids": (1, 2), **fields})


class TestJunction:
    def test_pair_is_unordered(self) -> None:
        assert Junction(3, 8, 40).pair == Junction(8, 3, 12).pair

    @pytest.mark.parametrize(
        ("args", "fragment"),
        [((3, 3, 10), "joins a key image to itself"), ((3, 4, -1), "matches: expected an integer")],
    )
    def test_bad_fields(self, args: tuple[int, int, int], fragment: str) -> None:
        with pytest.raises(MemoryFormatError, match=fragment):
            Junction(*args)
