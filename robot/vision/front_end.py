"""The vision front end: one entry point for describing images and matching their points.

Teach (key image selection), the follower, localization and the two-view tool all
call a :class:`FrontEnd` made by :func:`make_front_end` from the ``[features]`` config
and the camera model:

* :meth:`FrontEnd.describe` ``(image, mask=None) -> Features``: points (pixels, unit
  bearings in the camera frame through the camera model, descriptors, responses)
  inside the lens's image circle;
* :meth:`FrontEnd.match` ``(feats_a, feats_b, matching, predicted=None) -> Matches``:
  mutually best pairs in a search window, optionally centred where a predicted
  rotation moves A's points;
* :meth:`FrontEnd.features_from_keyframe` and :func:`stored_descriptors`: the
  features a visual memory stores, back and forth; :func:`front_end_label` names what
  the descriptors are, which the memory records when taught
  (``VisualMemory.front_end``) and :func:`check_front_end` compares.

The method is ``FeatureConfig.method`` (docs/front-end.md compares them): the paper's
``harris-zncc`` (Courbon et al. 2008, sec. III-A) is the baseline and stays selectable.
A memory keeps the descriptors as float32 rows whatever the method (bit strings as
their byte values 0-255, exactly), so a memory is read back by the method that wrote it:
ORB, TEBLID and BEBLID all make 32 bytes, and a memory taught with one, followed with
another, would match noise against noise without a word; the label refuses it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, MatchConfig
from robot.vision.descriptors import DESCRIPTOR_BYTES, SIFT_LENGTH, Detector, opencv_detector
from robot.vision.features import (
    BoolImage,
    Descriptors,
    Features,
    GreyImage,
    PixelSizes,
    PixelsXY,
    detect_harris,
)
from robot.vision.lens_mask import lens_mask
from robot.vision.matching import Matches, match_features
from shared.camera_model import CameraModel
from shared.errors import MemoryFormatError, check_shape
from shared.memory import Keyframe, VisualMemory


class FrontEnd:
    """Describes images and matches features with one method and one camera (module docstring).

    Pure: arrays in, arrays out; no clock, no I/O.

    Args:
        config: the ``[features]`` table: the method and its parameters.
        camera: the lens of every image described (size, image circle, lift).
        mask: the lens's mask (:func:`robot.vision.lens_mask.lens_mask`) if the caller has
            it already; None computes it.
    """

    def __init__(self, config: FeatureConfig, camera: CameraModel,
                 mask: BoolImage | None = None) -> None:
        self.config = config
        self.camera = camera
        self.mask: BoolImage = lens_mask(camera) if mask is None else mask
        self.sizes = PixelSizes.for_camera(config, camera)
        self._detect: Detector = (detect_harris if config.method == "harris-zncc"
                                  else opencv_detector(config.method))
        self._binary = config.method not in ("harris-zncc", "sift")

    @property
    def method(self) -> str:
        """The method's name, one of ``robot.config.FRONT_END_METHODS``."""
        return self.config.method

    def describe(self, image: GreyImage, mask: BoolImage | None = None) -> Features:
        """Detect and describe the points of one image.

        Args:
            image: (H, W) uint8 grey image of the camera's size.
            mask: (H, W) bool, True where points may be; None = the lens's image circle.

        Returns:
            The features, strongest first, every one inside the mask.

        Raises:
            ShapeError: the image is not the camera's size, or the mask not the image's.
            TypeError: the image is not uint8 or the mask not bool.
        """
        image = np.asarray(image)
        check_shape("image", image.shape, (self.camera.height, self.camera.width))
        found = self._detect(image, self.config, self.mask if mask is None else mask, self.sizes)
        return self.features(found.pixels_xy, found.descriptors, found.response)

    def features(self, pixels_xy: PixelsXY, descriptors: Descriptors,
                 response: npt.ArrayLike | None = None) -> Features:
        """Features at given pixels, lifted through the camera model.

        Args:
            pixels_xy: (N, 2) px.
            descriptors: (N, D) of this front end's method.
            response: (N,) detector responses; None = zeros (stored key images).

        Raises:
            ShapeError: inconsistent shapes.
        """
        pixels_xy = np.asarray(pixels_xy, dtype=np.float64)
        check_shape("pixels_xy", pixels_xy.shape, (None, 2))
        bearings, valid = self.camera.lift(pixels_xy)
        bearings[~valid] = (0.0, 0.0, 1.0)
        n = pixels_xy.shape[0]
        return Features(pixels_xy, descriptors,
                        np.zeros(n, np.float32) if response is None else response, bearings)

    @property
    def descriptor_length(self) -> int:
        """D: values per descriptor (bytes of a bit string, floats of a row)."""
        if self.method == "harris-zncc":
            return self.sizes.patch_px ** 2
        return SIFT_LENGTH if self.method == "sift" else DESCRIPTOR_BYTES[self.method]

    def features_from_keyframe(self, keyframe: Keyframe) -> Features:
        """A key image's stored points and descriptors (see :func:`stored_descriptors`).

        Raises:
            MemoryFormatError: the key image's descriptors are not this method's (a memory
                taught with another front end, or another lens).
        """
        if keyframe.descriptor_length != self.descriptor_length:
            raise MemoryFormatError(
                f"key image {keyframe.id}",
                f"descriptors have {keyframe.descriptor_length} values, the front end "
                f"{self.method!r} on this lens makes {self.descriptor_length}: the memory was "
                f"taught with another [features] method or lens (set that method, e.g. "
                f"'harris-zncc' for memories taught before ORB became the default, or teach "
                f"again)")
        return self.features(keyframe.pixels_xy, self.descriptors_from_stored(keyframe.patches))

    def descriptors_from_stored(self, stored: npt.NDArray[np.float32]) -> Descriptors:
        """(N, D) descriptors of this method from a memory's float32 rows
        (:func:`stored_descriptors` undone)."""
        return np.asarray(stored).astype(np.uint8) if self._binary else np.asarray(stored)

    def match(self, feats_a: Features, feats_b: Features, matching: MatchConfig,
              predicted: npt.ArrayLike | None = None) -> Matches:
        """Mutually best matches of A's features with B's (:func:`match_features`).

        Args:
            feats_a: features of image A.
            feats_b: features of image B, same method.
            matching: window, threshold and ratio test.
            predicted: (3, 3) R_b_a, the rotation from camera A's frame to camera B's
                expected between the two images (e.g. from odometry): each of A's
                points is searched for around where the rotation turns its bearing.
                None = around its own bearing.

        Returns:
            The matches (index pairs and similarities).
        """
        if self._binary:
            matching = dataclasses.replace(
                matching, min_zncc=1.0 - 2.0 * self.config.max_hamming_fraction)
        return match_features(feats_a, feats_b, matching, predicted)


def front_end_label(config: FeatureConfig, camera: CameraModel) -> str:
    """What the descriptors of ``config``'s front end on ``camera`` are: the method and the
    window they describe, px on this lens (e.g. ``"orb, 31 px window"``). Descriptors of two
    front ends with the same label may be compared; a memory records it when taught."""
    sizes = PixelSizes.for_camera(config, camera)
    if config.method == "harris-zncc":
        return f"harris-zncc, {sizes.patch_px} px patches"
    if config.method in ("sift", "akaze"):
        return config.method
    return f"{config.method}, {sizes.descriptor_px} px window"


def check_front_end(memory: VisualMemory, config: FeatureConfig) -> None:
    """Refuse a memory whose key images another front end than ``config``'s described (the
    :attr:`VisualMemory.front_end` it records; a memory that records none passes).

    Raises:
        MemoryFormatError: the memory records another front end (one line: both, and what
            to set).
    """
    label = front_end_label(config, memory.camera)
    if memory.front_end is not None and memory.front_end != label:
        method = memory.front_end.split(",")[0]
        raise MemoryFormatError(
            "visual memory",
            f"its key images were described by front end {memory.front_end!r}, the config's "
            f"[features] makes {label!r}: set [features] method = {method!r} (and its window) "
            f"as when it was taught, or teach again")


def make_front_end(config: FeatureConfig, camera: CameraModel,
                   mask: BoolImage | None = None) -> FrontEnd:
    """The front end of ``config.method`` for images of ``camera`` (module docstring);
    ``mask``: the lens mask if already computed."""
    return FrontEnd(config, camera, mask)


def stored_descriptors(features: Features) -> npt.NDArray[np.float32]:
    """(N, D) float32 descriptors as a memory stores them (bit strings as byte values)."""
    return np.array(features.descriptors, dtype=np.float32)
