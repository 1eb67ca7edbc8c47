"""Localization in the visual memory: which key image is the robot's view?

Courbon et al. (ICARCV 2008, sec. II-D): "Points between the current and a key
image are matched. The distance between these images is the inverse of the
number of matched points", and the key image with the most matches is the
localization result (sec. IV: 306 matches, 6.5 s against 280 key images).

That rule costs one full matching per key image. Here it is kept as the final
decision but applied to a few candidates picked by a cheap global prefilter:

1. **Prefilter** (vectorised over the whole memory, descriptors precomputed
   once in :class:`Localizer`). Each key image's 80x60 thumbnail is patch
   normalised, z = (I - local mean) / (local std + eps) over a small window, as
   SeqSLAM (Milford and Wyeth, ICRA 2012) and the QVPR teach-and-repeat system
   (Dall'Osto et al., IROS 2021) do with tiny images; pixels outside the lens
   circle and rows below ``prefilter_rows_fraction`` are dropped; the result is
   unit-normalised. The query's descriptor is compared shifted sideways by up to
   ``prefilter_max_shift_px`` (a turn of the robot shifts the view): similarity =
   the best cosine over the shifts, one (S, D) x (D, N) product.
2. **Verification**: Harris corners of the query matched by ZNCC with the
   mutual-best check (no search window by default) against the
   ``candidates`` most similar key images' stored corners; the winner has the
   most matches (ties: the more similar thumbnail). It is a localization
   (``ok``) with at least ``min_matches``.

:meth:`Localizer.localize_exhaustive` applies the paper's rule to every key
image, the baseline the benchmark compares speed and answers with.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, LocalizeConfig
from robot.vision.features import Features, GreyImage
from robot.vision.front_end import make_front_end
from shared.camera_model import CameraModel
from shared.memory import (
    THUMBNAIL_HEIGHT_PX,
    THUMBNAIL_WIDTH_PX,
    VisualMemory,
    thumbnail_from_image,
)

Descriptors = npt.NDArray[np.float32]
"""(N, D) float32 unit rows: global descriptors of N images."""

_NORMALISE_EPS = 2.0
"""Added to the local standard deviation (grey levels) so that flat areas do not amplify noise."""


@dataclass(frozen=True, slots=True)
class Candidate:
    """A key image verified by full matching.

    Attributes:
        keyframe_id: the key image.
        similarity: the prefilter's score, cosine in [-1, 1] (nan when not prefiltered).
        matches: ZNCC matches with the query (the paper's rule).
    """

    keyframe_id: int
    similarity: float
    matches: int


@dataclass(frozen=True, slots=True)
class Localization:
    """Where a query image is in the memory.

    Attributes:
        keyframe_id: the candidate with the most matches; None when there were no
            key images to compare with.
        matches: its number of matches (0 when ``keyframe_id`` is None).
        ok: whether ``matches`` reaches ``LocalizeConfig.min_matches``.
        candidates: the verified key images, most similar thumbnail first (all key
            images, in id order, for the exhaustive baseline).
        query_features: corners found in the query.
    """

    keyframe_id: int | None
    matches: int
    ok: bool
    candidates: tuple[Candidate, ...]
    query_features: int


class Localizer:
    """Localizes images among a fixed set of key images (see the module docstring).

    Building it precomputes the prefilter's descriptors (one pass over the
    thumbnails); each query then costs one corner detection, one matrix product
    and ``config.candidates`` matchings.

    Args:
        keyframe_ids: (N,) ids of the key images.
        thumbnails: their (60, 80) uint8 thumbnails
            (:func:`shared.memory.thumbnail_from_image`), in the same order.
        features: their Harris corners and ZNCC patches, in the same order.
        camera: the camera of the key images and of the queries.
        feature_config: how corners are detected in queries (as in the key images).
        config: prefilter and verification parameters.

    Raises:
        ValueError: the three sequences differ in length, or a thumbnail has the wrong shape.
    """

    def __init__(
        self,
        keyframe_ids: Sequence[int],
        thumbnails: Sequence[GreyImage],
        features: Sequence[Features],
        camera: CameraModel,
        feature_config: FeatureConfig,
        config: LocalizeConfig,
    ) -> None:
        if not len(keyframe_ids) == len(thumbnails) == len(features):
            raise ValueError(
                f"localizer: {len(keyframe_ids)} key image ids, {len(thumbnails)} thumbnails and "
                f"{len(features)} feature sets: expected one of each per key image",
            )
        self._ids = tuple(int(i) for i in keyframe_ids)
        self._features = tuple(features)
        self._camera = camera
        self._front_end = make_front_end(feature_config, camera)
        self._config = config
        self._mask = self._front_end.mask
        self._prefilter = _Prefilter(self._mask, config)
        self._descriptors = self._prefilter.describe_all(thumbnails)

    @classmethod
    def from_memory(
        cls,
        memory: VisualMemory,
        feature_config: FeatureConfig,
        config: LocalizeConfig,
        keyframe_ids: Iterable[int] | None = None,
    ) -> Localizer:
        """A localizer over the key images of ``memory`` (all, or ``keyframe_ids``).

        Raises:
            UnknownKeyframeError: an id of ``keyframe_ids`` is not in the memory.
        """
        ids = sorted(memory.keyframes) if keyframe_ids is None else list(keyframe_ids)
        keyframes = [memory.keyframe(i) for i in ids]
        front_end = make_front_end(feature_config, memory.camera)
        return cls(
            ids,
            [k.thumbnail for k in keyframes],
            [front_end.features_from_keyframe(k) for k in keyframes],
            memory.camera,
            feature_config,
            config,
        )

    @property
    def keyframe_ids(self) -> tuple[int, ...]:
        """The key images this localizer chooses from."""
        return self._ids

    def localize(self, image: GreyImage) -> Localization:
        """The key image that best fits ``image``: prefilter, then the paper's rule on candidates.

        Args:
            image: (H, W) uint8 grey query of the camera's size.

        Raises:
            ValueError: the image has the wrong size or type, or is empty.
        """
        query = self._query_features(image)
        if not self._ids:
            return Localization(None, 0, False, (), len(query))
        similarity = self._prefilter.similarity(thumbnail_from_image(image), self._descriptors)
        count = min(self._config.candidates, len(self._ids))
        # argpartition picks the best `count` in O(N); only those are sorted.
        best = np.argpartition(-similarity, count - 1)[:count]
        best = best[np.argsort(-similarity[best], kind="stable")]
        return self._decide(query, best, similarity)

    def localize_exhaustive(self, image: GreyImage) -> Localization:
        """The paper's rule over every key image: the one with the most matches (the baseline).

        Raises:
            ValueError: the image has the wrong size or type, or is empty.
        """
        query = self._query_features(image)
        if not self._ids:
            return Localization(None, 0, False, (), len(query))
        return self._decide(query, np.arange(len(self._ids)), None)

    def _decide(
        self,
        query: Features,
        order: npt.NDArray[np.intp],
        similarity: npt.NDArray[np.float32] | None,
    ) -> Localization:
        """Match ``query`` with the key images at positions ``order``; the most matches wins."""
        candidates = tuple(
            Candidate(
                keyframe_id=self._ids[k],
                similarity=float("nan") if similarity is None else float(similarity[k]),
                matches=len(self._front_end.match(query, self._features[k],
                                                  self._config.matching)),
            )
            for k in order
        )
        # max() keeps the first of equals: ties go to the more similar thumbnail.
        winner = max(candidates, key=lambda c: c.matches)
        return Localization(
            keyframe_id=winner.keyframe_id,
            matches=winner.matches,
            ok=winner.matches >= self._config.min_matches,
            candidates=candidates,
            query_features=len(query),
        )

    def _query_features(self, image: GreyImage) -> Features:
        image = np.asarray(image)
        size = (self._camera.height, self._camera.width)
        if image.dtype != np.uint8 or image.shape != size:
            raise ValueError(
                f"query image: expected a {size[1]}x{size[0]} uint8 grey image, got shape "
                f"{image.shape} "
                f"dtype {image.dtype}",
            )
        return self._front_end.describe(image)


class _Prefilter:
    """Patch-normalised thumbnails compared by cosine, with sideways shifts (step 1)."""

    def __init__(self, lens: npt.NDArray[np.bool_], config: LocalizeConfig) -> None:
        self._config = config
        self._rows = max(1, round(config.prefilter_rows_fraction * THUMBNAIL_HEIGHT_PX))
        # A thumbnail pixel is used only if the lens sees all of the pixels it averages.
        coverage = cv2.resize(
            lens.astype(np.float32), (THUMBNAIL_WIDTH_PX, THUMBNAIL_HEIGHT_PX),
            interpolation=cv2.INTER_AREA,
        )
        self._inside = (coverage >= 1.0 - 1e-6)[: self._rows]

    def describe_all(self, thumbnails: Sequence[GreyImage]) -> Descriptors:
        """(N, D) unit descriptors of key image thumbnails."""
        shape = (THUMBNAIL_HEIGHT_PX, THUMBNAIL_WIDTH_PX)
        rows = []
        for i, thumb in enumerate(thumbnails):
            if thumb.shape != shape or thumb.dtype != np.uint8:
                raise ValueError(
                    f"thumbnail {i}: expected {shape[1]}x{shape[0]} uint8, got shape "
                    f"{thumb.shape} dtype "
                    f"{thumb.dtype}",
                )
            rows.append(_unit(self._normalised(thumb).reshape(1, -1))[0])
        return np.stack(rows) if rows else np.zeros((0, self._inside.size), np.float32)

    def similarity(
        self, thumbnail: GreyImage, descriptors: Descriptors
    ) -> npt.NDArray[np.float32]:
        """(N,) best cosine between the query, shifted sideways, and each descriptor."""
        z = self._normalised(thumbnail)
        s = self._config.prefilter_max_shift_px
        padded = np.pad(z, ((0, 0), (s, s)))
        # shifted[k] is z moved right by s - k columns, zero-filled: (2s + 1, rows, W).
        shifted = np.lib.stride_tricks.sliding_window_view(padded, z.shape[1], axis=1)
        shifted = shifted.transpose(1, 0, 2).reshape(2 * s + 1, -1)
        scores: npt.NDArray[np.float32] = (_unit(shifted) @ descriptors.T).max(axis=0)
        return scores

    def _normalised(self, thumbnail: GreyImage) -> npt.NDArray[np.float32]:
        """(rows, W) float32: (I - local mean) / (local std + eps), zero outside the lens."""
        k = self._config.prefilter_window_px
        image = thumbnail.astype(np.float32)
        mean = cv2.blur(image, (k, k), borderType=cv2.BORDER_REFLECT)
        mean_sq = cv2.blur(image * image, (k, k), borderType=cv2.BORDER_REFLECT)
        std = np.sqrt(np.maximum(mean_sq - mean * mean, 0.0))
        z = ((image - mean) / (std + _NORMALISE_EPS))[: self._rows]
        return np.where(self._inside, z, np.float32(0.0)).astype(np.float32)


def _unit(rows: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
    """Rows scaled to unit norm (all-zero rows stay zero)."""
    norms = np.linalg.norm(rows, axis=1, keepdims=True)
    return (rows / np.where(norms > 0, norms, 1.0)).astype(np.float32)


def localize(
    memory: VisualMemory,
    image: GreyImage,
    feature_config: FeatureConfig,
    config: LocalizeConfig,
) -> Localization:
    """Localize one image in ``memory`` (builds a :class:`Localizer`; keep one for many queries).

    Args:
        memory: the visual memory.
        image: (H, W) uint8 grey query of the memory camera's size.
        feature_config: corner detection, as when the memory was taught.
        config: prefilter and verification parameters.

    Raises:
        ValueError: the image has the wrong size or type, or is empty.
    """
    return Localizer.from_memory(memory, feature_config, config).localize(image)
