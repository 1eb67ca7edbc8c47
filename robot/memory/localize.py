"""Localization in the visual memory: which key image is the robot's view?

Courbon et al. (ICARCV 2008, sec. II-D): "Points between the current and a key
image are matched. The distance between these images is the inverse of the
number of matched points", and the key image with the most matches is the
localization result (sec. IV: 306 matches, 6.5 s against 280 key images).

That rule costs one full matching per key image, and on real images a match
count cannot tell places apart (unrelated views share a median 30 chance
matches, issue 16). Here a cheap global prefilter picks a few candidates and
each is verified geometrically:

1. **Prefilter** (vectorised over the whole memory, descriptors precomputed
   once in :class:`Localizer`). Each key image's 80x60 thumbnail is patch
   normalised, z = (I - local mean) / (local std + eps) over a small window, as
   SeqSLAM (Milford and Wyeth, ICRA 2012) and the QVPR teach-and-repeat system
   (Dall'Osto et al., IROS 2021) do with tiny images; pixels outside the lens
   circle and rows below ``prefilter_rows_fraction`` are dropped; the result is
   unit-normalised. The query's descriptor is compared shifted sideways by up to
   ``prefilter_max_shift_px`` (a turn of the robot shifts the view): similarity =
   the best cosine over the shifts, one (S, D) x (D, N) product.
2. **Verification**: the query's features (:mod:`robot.vision.front_end`, the
   ``[features]`` method) matched with the mutual-best check (no search window by
   default) against the ``candidates`` most similar key images' stored features; the
   matched bearings are rotated into the mount's level frame and a relative pose is fitted
   (:mod:`robot.memory.verification`). A candidate is accepted on enough inliers,
   a high enough inlier ratio and a motion a ground robot can make.
3. **Path support**: the accepted candidate with the most inliers plus
   ``neighbour_weight`` times the inliers of its two path neighbours (accepted ones
   among the candidates) wins (ties: the more similar thumbnail); the result is a
   localization (``ok``) only if one was accepted. A view between key images is seen
   by several consecutive key images with nearly equal inliers where the scene is far
   (in the ``campus`` courtyard the most inliers alone picked a key image two away
   from the nearest in 8 of 200 views); the neighbours' support centres the answer on
   the run of key images that see the view, and an isolated look-alike elsewhere
   gets none (sequence-based place recognition uses the same idea over time: Milford
   and Wyeth's SeqSLAM). Candidates are verified lazily, best possible support first
   with match counts standing in for the inliers of those not yet verified, until the
   best support is known exactly (branch and bound).
4. **The walk along the path**: the fitted translation says on which side of the
   winner the query lies (ahead or behind it along the key image's forward axis, up
   to scale); the winner's path neighbours towards that side are verified one after
   the other (at most ``bracket_steps``; matched and verified now if the prefilter
   passed over them) until two consecutive ones bracket the query (the first sees it
   ahead, the next behind). Of the two, the one the query lies more
   beside than along is the answer (the nearest along the path), and the second, the
   first key image ahead of the query, is where a route from it starts
   (``Localization.ahead_id``: a route started at a key image the robot is level with
   begins with a target the follower cannot see ahead). Without a bracketing pair the
   winner stays the nearest, and the first ahead is the key image after the last one
   walked if the query lies ahead of them all. Forward views of a far scene
   give nearly equal inliers over several key images, which put the most inliers 2-3
   key images ahead of the nearest in 5 of 200 ``campus`` views; the sign of the
   translation does not fade with distance as the inlier counts' differences do.
5. **Other paths at the same place** (on request: ``each_path``): where visual paths run
   together (a loop leaving a corridor along it), the view is also one of another path's
   key images, and a route from there may be far shorter. Of each other path among the
   candidates, the one with the most matches is verified and, accepted, walked as in
   step 4 (``Localization.elsewhere``). Whether it is the same place and not a
   look-alike is for the memory's junctions to say
   (:func:`robot.memory.junctions.same_place`), and for the planner to use.

:meth:`Localizer.localize_exhaustive` applies the paper's rule (most matches) to
every key image and verifies its winner, the baseline the benchmark compares speed
and answers with.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, LocalizeConfig
from robot.memory.verification import Verification, verify_bearings
from robot.vision.features import Features, GreyImage
from robot.vision.front_end import check_front_end, make_front_end
from robot.vision.matching import Matches
from shared.camera_model import CameraModel
from shared.camera_mount import rotation_level_cam
from shared.config import CameraMountConfig
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
    """A key image matched with the query, and its geometric verification.

    Attributes:
        keyframe_id: the key image.
        similarity: the prefilter's score, cosine in [-1, 1] (nan when not prefiltered).
        matches: matches with the query (the front end's method).
        verification: the relative pose's inliers and the verdict; None when not
            verified (the exhaustive baseline verifies only its winner).
        support: its inliers plus ``LocalizeConfig.neighbour_weight`` times those of its
            path neighbours among the candidates (accepted ones only); nan when not known
            (not verified, a neighbour not verified, or the exhaustive baseline).
    """

    keyframe_id: int
    similarity: float
    matches: int
    verification: Verification | None
    support: float = float("nan")

    @property
    def inliers(self) -> int:
        """Verified inliers (0 when not verified)."""
        return 0 if self.verification is None else self.verification.inliers

    @property
    def accepted(self) -> bool:
        """Whether the verification accepted this key image as the query's place."""
        return self.verification is not None and self.verification.accepted


@dataclass(frozen=True, slots=True)
class Localization:
    """Where a query image is in the memory.

    Attributes:
        keyframe_id: the best candidate (accepted, then most path support, then the walk
            along its path to the nearest); None when there were no key images to compare
            with.
        matches: its number of matches (0 when ``keyframe_id`` is None).
        inliers: its verified inliers (0 when ``keyframe_id`` is None).
        ok: whether it passed the geometric verification (a localization).
        candidates: the key images matched (the prefilter's, and those the walks of
            steps 4 and 5 verified beyond them), best first: the walk's answer, then
            accepted ones by path support, then by inliers, then by matches (equal ones in
            prefilter order; all key images in id order for the exhaustive baseline).
        query_features: features found in the query.
        ahead_id: the first key image ahead of the query on ``keyframe_id``'s path, where
            a route from the query starts (the walk of step 4): ``keyframe_id`` itself, or
            its next key image when the query lies between the two; None with
            ``keyframe_id``.
        elsewhere: (nearest, first ahead) of step 5 on each other path that has an
            accepted candidate, by path id; empty unless asked for.
    """

    keyframe_id: int | None
    matches: int
    inliers: int
    ok: bool
    candidates: tuple[Candidate, ...]
    query_features: int
    ahead_id: int | None = None
    elsewhere: tuple[tuple[int, int], ...] = ()

    @property
    def verdict(self) -> str:
        """The winner's verdict (:mod:`robot.memory.verification`), or why there is none."""
        winner = next((c for c in self.candidates if c.keyframe_id == self.keyframe_id), None)
        if winner is None or winner.verification is None:
            return "no key images"
        return winner.verification.verdict

    @property
    def detail(self) -> str:
        """One line for people: the best key image, its scores and the verdict."""
        if self.keyframe_id is None:
            return "no key images to compare with"
        return (f"key image {self.keyframe_id}: {self.matches} matches, {self.inliers} verified "
                f"inliers ({self.verdict})")


class Localizer:
    """Localizes images among a fixed set of key images (see the module docstring).

    Building it precomputes the prefilter's descriptors (one pass over the
    thumbnails); each query then costs one corner detection, one matrix product
    and ``config.candidates`` matchings and relative pose fits.

    Args:
        keyframe_ids: (N,) ids of the key images.
        thumbnails: their (60, 80) uint8 thumbnails
            (:func:`shared.memory.thumbnail_from_image`), in the same order.
        features: their Harris corners and ZNCC patches, in the same order.
        camera: the camera of the key images and of the queries.
        mount: where that camera sits on the robot (its level frame is where the
            verification measures yaw and tilt).
        feature_config: how corners are detected in queries (as in the key images).
        config: prefilter and verification parameters.
        seed: seeds the verification's RANSAC afresh for every query, so that one
            image always gets the same answer.
        places: each key image's place on its path, (path id, index along the path), for
            the path support of step 3 and the walk of step 4; None or missing ids: none.

    Raises:
        ValueError: the three sequences differ in length, or a thumbnail has the wrong shape.
    """

    def __init__(
        self,
        keyframe_ids: Sequence[int],
        thumbnails: Sequence[GreyImage],
        features: Sequence[Features],
        camera: CameraModel,
        mount: CameraMountConfig,
        feature_config: FeatureConfig,
        config: LocalizeConfig,
        seed: int = 0,
        places: Mapping[int, tuple[int, int]] | None = None,
    ) -> None:
        if not len(keyframe_ids) == len(thumbnails) == len(features):
            raise ValueError(
                f"localizer: {len(keyframe_ids)} key image ids, {len(thumbnails)} thumbnails and "
                f"{len(features)} feature sets: expected one of each per key image",
            )
        self._ids = tuple(int(i) for i in keyframe_ids)
        self._index = {i: k for k, i in enumerate(self._ids)}
        self._places = {int(i): (int(path), int(index))
                        for i, (path, index) in (places or {}).items()}
        self._at = {place: i for i, place in self._places.items()}
        self._features = tuple(features)
        self._camera = camera
        self._R_level_cam = rotation_level_cam(mount)
        self._front_end = make_front_end(feature_config, camera)
        self._config = config
        self._seed = seed
        self._mask = self._front_end.mask
        self._prefilter = _Prefilter(self._mask, config)
        self._descriptors = self._prefilter.describe_all(thumbnails)

    @classmethod
    def from_memory(
        cls,
        memory: VisualMemory,
        mount: CameraMountConfig,
        feature_config: FeatureConfig,
        config: LocalizeConfig,
        keyframe_ids: Iterable[int] | None = None,
    ) -> Localizer:
        """A localizer over the key images of ``memory`` (all, or ``keyframe_ids``).

        Raises:
            UnknownKeyframeError: an id of ``keyframe_ids`` is not in the memory.
            MemoryFormatError: another front end than ``feature_config``'s described the
                memory (:func:`robot.vision.front_end.check_front_end`).
        """
        ids = sorted(memory.keyframes) if keyframe_ids is None else list(keyframe_ids)
        keyframes = [memory.keyframe(i) for i in ids]
        check_front_end(memory, feature_config)
        front_end = make_front_end(feature_config, memory.camera)
        return cls(
            ids,
            [k.thumbnail for k in keyframes],
            [front_end.features_from_keyframe(k) for k in keyframes],
            memory.camera,
            mount,
            feature_config,
            config,
            places={k.id: (k.path_id, k.index) for k in keyframes},
        )

    @property
    def keyframe_ids(self) -> tuple[int, ...]:
        """The key images this localizer chooses from."""
        return self._ids

    def localize(self, image: GreyImage, verify_all: bool = False,
                 each_path: bool = False) -> Localization:
        """The key image that best fits ``image``: prefilter, then verification of the candidates.

        Candidates are verified lazily (step 3 of the module docstring): one whose
        support cannot beat the best known support (counting match counts for the
        inliers of unverified candidates) is left unverified unless ``verify_all``.

        Args:
            image: (H, W) uint8 grey query of the camera's size.
            verify_all: verify every candidate (to show each one's scores).
            each_path: also find the view on the other paths among the candidates
                (step 5), at the cost of a verification or more per path.

        Raises:
            ValueError: the image has the wrong size or type, or is empty.
        """
        query = self._query_features(image)
        if not self._ids:
            return Localization(None, 0, 0, False, (), len(query))
        similarity = self._prefilter.similarity(thumbnail_from_image(image), self._descriptors)
        count = min(self._config.candidates, len(self._ids))
        # argpartition picks the best `count` in O(N); only those are sorted.
        chosen = np.argpartition(-similarity, count - 1)[:count]
        best = [int(k) for k in chosen[np.argsort(-similarity[chosen], kind="stable")]]
        matches = [self._front_end.match(query, self._features[k], self._config.matching)
                   for k in best]
        verifications: list[Verification | None] = [None] * count
        rng = np.random.default_rng(self._seed)
        position = {self._ids[k]: i for i, k in enumerate(best)}
        around = [[position[j] for j in self._path_neighbours(self._ids[k]) if j in position]
                  for k in best]
        weight = self._config.neighbour_weight

        def inliers(i: int, bound: bool) -> float:
            """Accepted inliers of candidate i; its match count, an upper bound, if unverified
            and ``bound``."""
            v = verifications[i]
            if v is None:
                return float(len(matches[i])) if bound else math.nan
            return float(v.inliers) if v.accepted else 0.0

        def support(i: int, bound: bool) -> float:
            return inliers(i, bound) + weight * sum(inliers(j, bound) for j in around[i])

        if verify_all:
            for i in range(count):
                verifications[i] = self._verify(query, best[i], matches[i], rng)
        while True:
            # Branch and bound: the candidate whose support could be the highest (match
            # counts standing in for unverified inliers) is verified with its neighbours,
            # until the highest is known exactly; refused candidates cannot win.
            open_ = [i for i in range(count)
                     if verifications[i] is None or verifications[i].accepted]
            if not open_:
                break
            top = max(open_, key=lambda i: support(i, True))  # first of equals: prefilter order
            pending = [j for j in [top, *(around[top] if weight > 0 else [])]
                       if verifications[j] is None]
            if not pending:
                break
            for j in pending:
                verifications[j] = self._verify(query, best[j], matches[j], rng)

        def candidates() -> list[Candidate]:
            return [Candidate(self._ids[k], float(similarity[k]), len(m), v,
                              support(i, False) if v is not None and v.accepted else math.nan)
                    for i, (k, m, v) in enumerate(zip(best, matches, verifications, strict=True))]

        def verified(keyframe_id: int) -> Verification | None:
            """A key image's verification, verified now if it was not (a key image the
            prefilter passed over joins the candidates); None if it is not one of ours."""
            i = position.get(keyframe_id)
            if i is None:
                k = self._index.get(keyframe_id)
                if k is None:
                    return None
                i = position[keyframe_id] = len(best)
                best.append(k)
                matches.append(self._front_end.match(query, self._features[k],
                                                     self._config.matching))
                verifications.append(None)
                around.append([])
            if verifications[i] is None:
                verifications[i] = self._verify(query, best[i], matches[i], rng)
            return verifications[i]

        ranked = _ranked(candidates(), len(query))
        if not ranked.ok:
            return ranked
        nearest, ahead = self._walk(ranked.keyframe_id, verified)  # may verify more candidates
        elsewhere = []
        if each_path:
            for other in self._other_paths(ranked.keyframe_id, best, matches):
                verification = verified(other)
                if verification is not None and verification.accepted:
                    elsewhere.append(self._walk(other, verified))
        return _ranked(candidates(), len(query), first=nearest, ahead=ahead,
                       elsewhere=tuple(elsewhere))

    def _other_paths(self, winner: int, best: Sequence[int],
                     matches: Sequence[Matches]) -> list[int]:
        """Step 5's candidates: of each path but ``winner``'s, the candidate (positions
        ``best`` into the key images, their ``matches``) with the most matches, by path id."""
        own = self._places.get(winner, (None, 0))[0]
        most: dict[int, tuple[int, int]] = {}
        for k, m in zip(best, matches, strict=True):
            place = self._places.get(self._ids[k])
            if place is not None and place[0] != own and len(m) > most.get(place[0], (-1, 0))[0]:
                most[place[0]] = (len(m), self._ids[k])
        return [most[path][1] for path in sorted(most)]

    def _path_neighbours(self, keyframe_id: int) -> list[int]:
        """The key images before and after one on its path (none without its place)."""
        place = self._places.get(keyframe_id)
        if place is None:
            return []
        path, index = place
        return [self._at[(path, j)] for j in (index - 1, index + 1) if (path, j) in self._at]

    def _walk(self, winner: int,
              verified: Callable[[int], Verification | None]) -> tuple[int, int]:
        """Step 4: the key images of ``winner``'s path nearest the query and first ahead of
        it (module docstring). When no pair near it brackets the query, ``winner`` is the
        nearest, and the first ahead is ``winner`` too, unless the query lies ahead of
        every key image walked: then the one after the last of them."""
        own = verified(winner)
        if own is None or winner not in self._places or math.isnan(own.along):
            return winner, winner
        path, index = self._places[winner]
        step = 1 if own.along > 0 else -1
        previous, previous_along = winner, own.along
        for n in range(1, self._config.bracket_steps + 1):
            k = self._at.get((path, index + step * n))
            v = None if k is None else verified(k)
            if k is None or v is None or not v.accepted:
                break
            if math.isnan(v.along):  # no translation: the query stands at k
                return k, k
            if (v.along > 0) != (previous_along > 0):
                # Along-track nearer the one it lies more beside; the one ahead sees it behind.
                nearest = previous if abs(previous_along) <= abs(v.along) else k
                return nearest, previous if previous_along < 0 else k
            previous, previous_along = k, v.along
        beyond = self._at.get((path, self._places[previous][1] + 1)) if step > 0 else None
        return winner, winner if beyond is None else beyond

    def localize_exhaustive(self, image: GreyImage) -> Localization:
        """The paper's rule over every key image: the one with the most matches (the baseline),
        verified alone.

        Raises:
            ValueError: the image has the wrong size or type, or is empty.
        """
        query = self._query_features(image)
        if not self._ids:
            return Localization(None, 0, 0, False, (), len(query))
        matches = [self._front_end.match(query, f, self._config.matching) for f in self._features]
        # argmax keeps the first of equals: ties go to the lower id.
        k = int(np.argmax([len(m) for m in matches]))
        verification = self._verify(query, k, matches[k], np.random.default_rng(self._seed))
        candidates = [
            Candidate(i, float("nan"), len(m), verification if j == k else None)
            for j, (i, m) in enumerate(zip(self._ids, matches, strict=True))
        ]
        winner = candidates[k]
        return Localization(winner.keyframe_id, winner.matches, winner.inliers, winner.accepted,
                            tuple(candidates), len(query), winner.keyframe_id)

    def _verify(
        self, query: Features, k: int, matches: Matches, rng: np.random.Generator
    ) -> Verification:
        """Verify ``matches`` of ``query`` with the key image at position ``k``."""
        return verify_matches(query, self._features[k], matches, self._R_level_cam,
                              self._config, rng)

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


def verify_matches(
    query: Features,
    key: Features,
    matches: Matches,
    R_level_cam: npt.NDArray[np.float64],
    config: LocalizeConfig,
    rng: np.random.Generator,
) -> Verification:
    """Localization's acceptance test of one query / key image pair (step 2 of the module
    docstring): the matched points' bearings in the level frame, a relative pose judged.

    Args:
        query: the query's features (bearings through the camera model).
        key: the key image's features (same camera).
        matches: their matches (``idx_a`` into ``query``, ``idx_b`` into ``key``).
        R_level_cam: (3, 3) camera -> level frame of the mount
            (:func:`shared.camera_mount.rotation_level_cam`).
        config: the acceptance thresholds.
        rng: draws RANSAC's samples.
    """
    R = np.asarray(R_level_cam, dtype=np.float64)
    return verify_bearings(query.bearings[matches.idx_a] @ R.T,
                           key.bearings[matches.idx_b] @ R.T, rng, config)


def _ranked(candidates: Sequence[Candidate], query_features: int,
            first: int | None = None, ahead: int | None = None,
            elsewhere: tuple[tuple[int, int], ...] = ()) -> Localization:
    """The localization of verified candidates in prefilter order (see :class:`Localization`),
    key image ``first`` (the walk's nearest) ahead of the ranking where given, ``ahead``
    the walk's first key image ahead (the winner where not given), and step 5's
    ``elsewhere``."""
    # sorted(reverse=True) is stable: equals keep the prefilter's order (the more similar first).
    ranked = sorted(candidates, key=lambda c: (
        c.keyframe_id == first, c.accepted,
        c.support if c.accepted and not math.isnan(c.support) else c.inliers,
        c.inliers, c.matches), reverse=True)
    winner = ranked[0]
    return Localization(winner.keyframe_id, winner.matches, winner.inliers, winner.accepted,
                        tuple(ranked), query_features,
                        winner.keyframe_id if ahead is None else ahead, elsewhere)


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
    mount: CameraMountConfig,
    feature_config: FeatureConfig,
    config: LocalizeConfig,
) -> Localization:
    """Localize one image in ``memory`` (builds a :class:`Localizer`; keep one for many queries).

    Args:
        memory: the visual memory.
        image: (H, W) uint8 grey query of the memory camera's size.
        mount: where the camera sits on the robot.
        feature_config: corner detection, as when the memory was taught.
        config: prefilter and verification parameters.

    Raises:
        ValueError: the image has the wrong size or type, or is empty.
    """
    return Localizer.from_memory(memory, mount, feature_config, config).localize(image)
