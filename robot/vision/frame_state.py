"""The per-frame vision pipeline: the current frame's corners to (y, theta) and the image errors.

DESIGN.md sec. 5.5 and 5.7; Courbon et al. 2008, sec. III-B to IV. Two stages:

* **Once per key image** the robot heads for, :func:`key_segment_from_key_images`:
  the next key image's corners are lifted to level bearings, and the metric
  structure of the next key image with another one (the previous key image, or
  the one after next on a path's first segment) is triangulated
  (:func:`robot.vision.key_pair.key_pair_geometry`) from their correspondences:
  the corners tracked frame to frame while teaching (``Keyframe.tracked_from_previous``,
  :mod:`robot.teach`) when the memory has them, plus front-end matches among the corners
  the tracks leave out (:func:`key_correspondences`). Matching the two key images
  alone finds too few pairs where the view changes fast (measured on ``lab``
  key images by ``vmnav bench vision``).
* **Per frame**, :func:`state_from_frame`: the current frame's corners are matched
  with the next key image's (:meth:`robot.vision.front_end.FrontEnd.match` in the
  ``PathStateConfig.matching`` window, mutual best), lifted, and the state comes from
  :func:`robot.vision.path_state.state_from_views`; the paper's image errors
  errImageMax and errPoints (:mod:`robot.vision.image_errors`) are measured on the
  matches the estimate keeps as epipolar inliers.

Detection stays with the caller, which describes each frame once
(:meth:`robot.vision.front_end.FrontEnd.describe`, inside the lens's image circle).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from robot.config import MatchConfig, PathStateConfig
from robot.vision.bearings import LevelBearings, level_bearings
from robot.vision.features import Features
from robot.vision.front_end import FrontEnd
from robot.vision.image_errors import ImageErrors, image_errors
from robot.vision.key_pair import KeyPairGeometry, key_pair_geometry
from robot.vision.path_state import PathState, state_from_views
from shared.camera_mount import rotation_level_cam
from shared.config import CameraMountConfig
from shared.errors import check_shape
from shared.pose import Pose2

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class KeyCorrespondences:
    """Pairs of corners of the next key image and another key image.

    Attributes:
        idx_next: (K,) int64 corner indices in the next key image, each at most once.
        idx_other: (K,) int64 the paired corners of the other key image, each at most once.
        n_tracked: how many of the pairs (the first ones) come from the teach tracks.
    """

    idx_next: IntArray
    idx_other: IntArray
    n_tracked: int


@dataclass(frozen=True, eq=False)
class KeySegment:
    """What the per-frame estimate reuses while the robot heads for one key image.

    Attributes:
        next_features: the next key image's corners and descriptors.
        next_bearings: the next key image's corners as level bearings, with validity.
        correspondences: the next key image's pairs with the other key image.
        key_pair: their metric structure; the state is not ok without it.
    """

    next_features: Features
    next_bearings: LevelBearings
    correspondences: KeyCorrespondences
    key_pair: KeyPairGeometry


@dataclass(frozen=True, eq=False)
class FrameState:
    """The vision's answer for one frame.

    Attributes:
        state: y, theta, s relative to the next key image (``ok`` says whether usable).
        image_errors: errImageMax and errPoints over the epipolar inliers of the
            estimate, px (inf when there are none).
        matches: corners of the frame matched with the next key image (valid rays).
        matched_xy: (matches, 2) float64 pixels of those corners in the frame, in the
            order of ``state.inlier_mask`` (for display: the robot's live view).
        key_xy: (matches, 2) float64 pixels of the next key image's corners they were
            matched with, same order (for display beside the key image).
    """

    state: PathState
    image_errors: ImageErrors
    matches: int
    matched_xy: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    key_xy: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))


def key_correspondences(
    next_features: Features,
    other_features: Features,
    front_end: FrontEnd,
    matching: MatchConfig,
    tracks_next_other: npt.ArrayLike | None = None,
) -> KeyCorrespondences:
    """Pair the corners of two key images: teach tracks first, then matches among the rest.

    Args:
        next_features: N corners of the next key image.
        other_features: M corners of the other key image.
        front_end: the front end that described both.
        matching: matching of the corners no track pairs.
        tracks_next_other: (T, 2) int (next key image's corner, other's corner)
            tracked while teaching, or None. The memory stores them on the later
            key image as (earlier corner, later corner): for the previous key image
            as the other, pass the next key image's ``tracked_from_previous[:, ::-1]``;
            for the one after next, its ``tracked_from_previous`` as is.

    Returns:
        The tracks, then the mutually best matches among the corners that no
        track uses.

    Raises:
        ShapeError: ``tracks_next_other`` is not (T, 2).
        ValueError: a track refers to a corner that does not exist.
    """
    tracks = np.zeros((0, 2), np.int64) if tracks_next_other is None else np.asarray(
        tracks_next_other, dtype=np.int64)
    check_shape("tracks_next_other", tracks.shape, (None, 2))
    for column, name, n in ((0, "next", len(next_features)), (1, "other", len(other_features))):
        if tracks.size and not (tracks[:, column].min() >= 0 and tracks[:, column].max() < n):
            raise ValueError(f"tracks_next_other: column {column} must index the {n} corners of "
                             f"the {name} key image, got "
                             f"{tracks[:, column].min()}..{tracks[:, column].max()}")
    free_next = np.setdiff1d(np.arange(len(next_features)), tracks[:, 0])
    free_other = np.setdiff1d(np.arange(len(other_features)), tracks[:, 1])
    matches = front_end.match(next_features.subset(free_next), other_features.subset(free_other),
                              matching)
    return KeyCorrespondences(
        idx_next=np.concatenate([tracks[:, 0], free_next[matches.idx_a]]).astype(np.int64),
        idx_other=np.concatenate([tracks[:, 1], free_other[matches.idx_b]]).astype(np.int64),
        n_tracked=len(tracks),
    )


def key_segment_from_key_images(
    next_features: Features,
    other_features: Features,
    odom_next: Pose2,
    odom_other: Pose2,
    front_end: FrontEnd,
    mount: CameraMountConfig,
    rng: np.random.Generator,
    config: PathStateConfig,
    tracks_next_other: npt.ArrayLike | None = None,
) -> KeySegment:
    """Prepare the per-frame estimate for heading to the next key image.

    Args:
        next_features: the next key image's corners and descriptors.
        other_features: the previous key image's (or, on a path's first segment,
            the key image after next).
        odom_next: teach odometry base pose of the next key image.
        odom_other: teach odometry base pose of the other key image, same frame.
        front_end: the front end of both key images (and their lens).
        mount: where the camera sits on the robot.
        rng: draws the RANSAC samples.
        config: matching window and geometry thresholds.
        tracks_next_other: teach tracks between the two, see :func:`key_correspondences`.

    Returns:
        The segment; its ``key_pair.ok`` is False (an expected outcome) when the two
        key images do not give a trustworthy structure.

    Raises:
        ShapeError, ValueError: bad ``tracks_next_other``.
        DegenerateGeometryError: the odometry puts the two optical centres less
            than 1 cm apart.
    """
    R_level_cam = rotation_level_cam(mount)
    pairs = key_correspondences(next_features, other_features, front_end, config.matching,
                                tracks_next_other)
    camera = front_end.camera
    next_bearings = level_bearings(camera, next_features.pixels_xy, R_level_cam)
    other = level_bearings(camera, other_features.pixels_xy[pairs.idx_other], R_level_cam)
    valid = next_bearings.valid[pairs.idx_next] & other.valid
    key_pair = key_pair_geometry(
        next_bearings.bearings[pairs.idx_next[valid]], other.bearings[valid],
        pairs.idx_next[valid], odom_next, odom_other, mount, rng, config,
    )
    return KeySegment(next_features=next_features, next_bearings=next_bearings,
                      correspondences=pairs, key_pair=key_pair)


def state_from_frame(
    current: Features,
    segment: KeySegment,
    front_end: FrontEnd,
    mount: CameraMountConfig,
    rng: np.random.Generator,
    config: PathStateConfig,
) -> FrameState:
    """The state and image errors of one frame (see the module docstring).

    Args:
        current: the frame's features (inside the lens mask).
        segment: the key image the robot heads for, prepared once.
        front_end: the front end that described the frame and the key images.
        mount: where the camera sits on the robot.
        rng: draws the RANSAC samples.
        config: matching window and geometry thresholds.

    Returns:
        The state (``ok`` False when the views do not give one) and the image errors.
    """
    matches = front_end.match(current, segment.next_features, config.matching)
    lifted = level_bearings(front_end.camera, current.pixels_xy[matches.idx_a],
                            rotation_level_cam(mount))
    valid = lifted.valid & segment.next_bearings.valid[matches.idx_b]
    idx_current, idx_next = matches.idx_a[valid], matches.idx_b[valid]
    state = state_from_views(lifted.bearings[valid], segment.next_bearings.bearings[idx_next],
                             idx_next, segment.key_pair, mount, rng, config)
    inliers = state.inlier_mask
    errors = image_errors(current.pixels_xy[idx_current[inliers]],
                          segment.next_features.pixels_xy[idx_next[inliers]])
    return FrameState(state=state, image_errors=errors, matches=len(idx_current),
                      matched_xy=current.pixels_xy[idx_current],
                      key_xy=segment.next_features.pixels_xy[idx_next])
