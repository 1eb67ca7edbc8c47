"""Matching of two feature sets in a search window on the sphere, with the unicity constraint.

Every front-end method's descriptors are compared as a *similarity* in [-1, 1]:
the dot product of unit rows (ZNCC for the paper's patches, cosine for SIFT), or
1 - 2 d / bits for packed bit strings at Hamming distance d (ORB, AKAZE, TEBLID,
BEBLID). The paper's ZNCC matching below is the same procedure with that score.

Courbon et al. (ICARCV 2008, sec. III-A): "For an interest point P1 at coordinates
(x y) in image Ii, we define a search region in image Ii+1. The search region is a
rectangle whose center has coordinates (x y). For each interest point P2 inside
the search region [...] we compute a score between the neighborhoods of P1 and P2
using a Zero Normalized Cross Correlation. The point with the best score and upper
than a threshold is kept as a good match and the unicity constraint is used to
reject matches which have become impossible."

Departures (docs/front-end.md):

* the search region is a cone on the sphere, not a pixel rectangle: B's point j is
  a candidate for A's point i when the angle between their bearings is at most
  ``search_radius_deg``, so a change of lens changes nothing (a pixel window of
  +-40 px was 13 degrees on the simulated lens and 4-6 degrees on real ones). A
  predicted rotation R_b_a (odometry) turns A's bearings first: a guided search;
* the unicity constraint is the mutual-best check: (i, j) is kept only if j is
  i's best candidate and i is j's best candidate, so no index appears twice;
* the optional ratio test (Lowe, IJCV 2004, sec. 7.1) compares the best candidate
  with the best one *outside a cone of* ``ratio_exclusion_deg`` around it: a corner's
  own neighbours (the same corner seen one pixel off, or its twin across a thin
  line) look alike and would otherwise reject every match; a repeated pattern's
  next period lies outside the cone and is what the test is for.

How it is vectorised: the (N, M) cosines of the bearings (one 3-column product)
give the candidate pairs; only those get a descriptor comparison; the scores land
in an (N, M) matrix, -inf where not a candidate, and row and column argmaxes give
the mutual bests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from robot.config import MatchConfig
from robot.vision.features import Features, PixelsXY
from shared.errors import ShapeError, check_shape

Indices = npt.NDArray[np.intp]
"""(K,) feature indices."""
Scores = npt.NDArray[np.float32]
"""(K,) float32 similarities in [-1, 1] (ZNCC for the paper's patches)."""
ScoreMatrix = npt.NDArray[np.float32]
"""(N, M) float32 similarities, -inf where (i, j) is not a candidate."""




@dataclass(frozen=True, slots=True, eq=False)
class Matches:
    """Mutually best matches between features A and B, in A's order (read-only arrays).

    Attributes:
        idx_a: (K,) indices into features A, increasing, each at most once.
        idx_b: (K,) indices into features B, each at most once.
        score: (K,) float32 similarities of the pairs, in [-1, 1] (module docstring).
    """

    idx_a: Indices
    idx_b: Indices
    score: Scores

    def __post_init__(self) -> None:
        # Views, so that making them read-only leaves the caller's arrays alone.
        idx_a = np.asarray(self.idx_a, dtype=np.intp).view()
        idx_b = np.asarray(self.idx_b, dtype=np.intp).view()
        score = np.asarray(self.score, dtype=np.float32).view()
        check_shape("idx_a", idx_a.shape, (None,))
        check_shape("idx_b", idx_b.shape, idx_a.shape)
        check_shape("score", score.shape, idx_a.shape)
        for name, array in (("idx_a", idx_a), ("idx_b", idx_b), ("score", score)):
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def __len__(self) -> int:
        return int(self.idx_a.shape[0])

    def pixels_xy(self, feats_a: Features, feats_b: Features) -> tuple[PixelsXY, PixelsXY]:
        """The matched corner positions.

        Args:
            feats_a: the features these matches index as A.
            feats_b: the features these matches index as B.

        Returns:
            ``(pixels_a_xy, pixels_b_xy)``, each (K, 2) float64 px; row k of both is match k.
        """
        return feats_a.pixels_xy[self.idx_a], feats_b.pixels_xy[self.idx_b]


def match_features(feats_a: Features, feats_b: Features, config: MatchConfig,
                   R_b_a: npt.ArrayLike | None = None) -> Matches:
    """Match features A to features B by similarity, window, threshold and mutual best.

    Args:
        feats_a: N features of image A.
        feats_b: M features of image B, with descriptors of the same length and kind.
        config: search radius (degrees, or None for the whole sphere), minimum
            similarity, optional ratio test.
        R_b_a: (3, 3) rotation from camera A's frame to camera B's expected between the
            two images: A's bearings are turned by it before the window applies (a
            guided search); None = no rotation.

    Returns:
        The K <= min(N, M) pairs (i, j) such that B's j lies in A's i search cone,
        j is i's best-scoring candidate, i is j's best-scoring candidate, the score
        is >= ``config.min_zncc`` and, if enabled, the ratio test passes. Ties go to
        the nearer bearing, then to the lower index. Empty when either side has no
        features.

    Raises:
        ShapeError: the two feature sets have descriptors of different lengths or kinds,
            or ``R_b_a`` is not (3, 3).
    """
    da, db = feats_a.descriptors, feats_b.descriptors
    if da.shape[1] != db.shape[1] or da.dtype != db.dtype:
        raise ShapeError(
            f"feats_a/feats_b: descriptors differ, {da.shape[1]} x {da.dtype} "
            f"and {db.shape[1]} x {db.dtype}"
        )
    rays_a = feats_a.bearings
    if R_b_a is not None:
        R = np.asarray(R_b_a, dtype=np.float64)
        check_shape("R_b_a", R.shape, (3, 3))
        rays_a = rays_a @ R.T
    n, m = len(feats_a), len(feats_b)
    if n == 0 or m == 0:
        return Matches(np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0, np.float32))
    cosines = rays_a @ feats_b.bearings.T
    if config.search_radius_deg is None:
        scores = _all_scores(feats_a, feats_b)
    else:
        cand_a, cand_b = np.nonzero(cosines >= math.cos(math.radians(config.search_radius_deg)))
        scores = np.full((n, m), -np.inf, dtype=np.float32)
        scores[cand_a, cand_b] = _pair_scores(feats_a, feats_b, cand_a, cand_b)

    # Equal scores (bit strings take few values; a pattern repeats) go to the nearer
    # bearing: the tie-break is far below the scores' resolution (2 / 256 for 256 bits).
    ranked = scores + np.float32(_TIE_BREAK) * cosines.astype(np.float32)
    rows = np.arange(n)
    best_b = ranked.argmax(axis=1)
    best_a = ranked.argmax(axis=0)
    best_score = scores[rows, best_b]
    keep = (best_a[best_b] == rows) & (best_score >= config.min_zncc)
    if config.max_distance_ratio is not None:
        second = _second_best_apart(scores, feats_b.bearings, best_b,
                                    config.ratio_exclusion_deg)
        keep &= _passes_ratio_test(best_score, second, config.max_distance_ratio,
                                   feats_a.binary)
    return Matches(rows[keep], best_b[keep], best_score[keep])


#: Weight of the bearings' cosine added to the scores to break ties, far below any score gap.
_TIE_BREAK = 1e-5


def _all_scores(feats_a: Features, feats_b: Features) -> ScoreMatrix:
    """(N, M) similarity of every pair (module docstring)."""
    if not feats_a.binary:
        return feats_a.descriptors @ feats_b.descriptors.T
    words_a, words_b = _words(feats_a.descriptors), np.ascontiguousarray(
        _words(feats_b.descriptors).T)
    # One word at a time: (N, M) contiguous XORs and popcounts, 5 times faster than one
    # (N, M, W) array summed over its last axis.
    hamming = np.zeros((len(words_a), words_b.shape[1]), dtype=np.int32)
    for w in range(words_b.shape[0]):
        hamming += np.bitwise_count(words_a[:, w, None] ^ words_b[w][None, :])
    return _from_hamming(hamming, feats_a.descriptors.shape[1])


def _pair_scores(feats_a: Features, feats_b: Features, idx_a: Indices, idx_b: Indices) -> Scores:
    """(K,) similarity of the pairs (idx_a[k], idx_b[k])."""
    da, db = feats_a.descriptors, feats_b.descriptors
    if not feats_a.binary:
        return np.einsum("kd,kd->k", da[idx_a], db[idx_b]).astype(np.float32)
    wa, wb = _words(da), _words(db)
    hamming = np.bitwise_count(wa[idx_a] ^ wb[idx_b]).sum(axis=1, dtype=np.int32)
    return _from_hamming(hamming, da.shape[1])


def _words(bits: npt.NDArray[np.uint8]) -> npt.NDArray[Any]:
    """(N, D) packed bytes as (N, D / 8) uint64 words (or (N, D) bytes if D is not a multiple
    of 8), for a popcount per word."""
    if bits.shape[1] % 8 == 0:
        return np.ascontiguousarray(bits).view(np.uint64)
    return bits


def _from_hamming(hamming: npt.NDArray[np.int32], n_bytes: int) -> npt.NDArray[np.float32]:
    """Similarity 1 - 2 d / bits of bit strings of ``n_bytes`` bytes at Hamming distance d."""
    return (1.0 - hamming.astype(np.float32) * np.float32(2.0 / (8 * n_bytes))).astype(np.float32)


def _second_best_apart(scores: ScoreMatrix, bearings_b: npt.NDArray[np.float64],
                       best_b: Indices, exclusion_deg: float) -> Scores:
    """(N,) each row's best score among B's points more than ``exclusion_deg`` from its best
    (-inf where there is none)."""
    near = bearings_b[best_b] @ bearings_b.T >= math.cos(math.radians(exclusion_deg))
    return np.where(near, -np.inf, scores).max(axis=1).astype(np.float32)


def _passes_ratio_test(best: Scores, second: Scores, max_ratio: float,
                       binary: bool) -> npt.NDArray[np.bool_]:
    """Lowe's ratio test (IJCV 2004, sec. 7.1) on descriptor distances.

    Unit rows: |p - q| = sqrt(2 - 2 similarity); bit strings: the Hamming distance,
    proportional to 1 - similarity. A match passes when its distance is below
    ``max_ratio`` times the second best's (always, when there is none).
    """
    if binary:
        best_dist, second_dist = 1.0 - best, 1.0 - second
    else:
        best_dist = np.sqrt(np.maximum(2.0 - 2.0 * best, 0.0))
        second_dist = np.sqrt(np.maximum(2.0 - 2.0 * second, 0.0))
    return best_dist < max_ratio * second_dist
