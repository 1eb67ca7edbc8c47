"""Key image selection while teaching: a stream of frames becomes a visual path.

Courbon et al. (ICARCV 2008, sec. II-C): "The first image of the video sequence
is selected as the first key frame I1. A key frame Ii+1 is then chosen so that
there are as many video frames as possible between Ii and Ii+1 while there are
at least M common interest points tracked between Ii and Ii+1."

Rules of this implementation (:class:`KeyImageSelector`):

1. **Tracked points.** The points of the last key image (the front end's,
   :mod:`robot.vision.front_end`; the paper's Harris corners) are tracked frame
   to frame: each frame's points are matched in a small window with the
   mutual-best check (:meth:`robot.vision.front_end.FrontEnd.match`, with
   ``TeachConfig.tracking``) against the points' latest positions and descriptors.
   A matched point moves to its match and takes its descriptor (the appearance
   drifts slowly as the view changes); an unmatched point keeps its last position
   and descriptor. A point dies after more than ``max_missed_frames`` consecutive frames
   without a match, so that one missed detection (noise, a person passing) does
   not end it. Corners are detected inside the lens's image circle only.
2. **Shared points.** A frame shares with the key image the tracked points
   matched *in that frame*. The live points (matched or in a short gap) never
   increase, and bound the shared ones from above. A new key image keeps its
   shared points as pairs (corner of the previous key image, its own corner):
   ``KeyframeRecord.tracked_from_previous``, the correspondences the three-view
   state estimate triangulates (:mod:`robot.vision.frame_state`). Tracked frame
   to frame they survive changes of view that matching the two key images
   directly does not: on the ``lab`` routes, 51 tracks per key image (median),
   72 correspondences with ZNCC matches added (minimum 57) against 47 (minimum
   19) from matching the key images alone (``vmnav bench vision``).
3. **Threshold.** M (``min_tracked_points``), but at most
   ``ceil(min_tracked_fraction * N)`` for a key image with N corners: where the
   scene is sparse (the ``campus`` corridor shows some 20-90 corners) a fixed M
   would make every frame a key image. This departs from the paper, whose M is
   fixed; with the defaults it changes nothing for key images of 143 corners or
   more. The fraction must stay well below the share of the live points that one
   frame matches (0.46-0.77 frame to frame in the ``lab`` and ``campus`` worlds,
   median about 0.6): at 0.5 the ``campus`` corridor path got 289 key images, 61
   of them under 5 cm apart, whose key pairs triangulate almost nothing (3 % ok
   against 97 % at 0.15-0.3 m), and the repeat went LOST within seconds.
4. **Choice.** While at least threshold points live, the latest frame sharing
   at least that many is the candidate. When fewer live, no later frame
   can share enough, so the candidate becomes the next key image and tracking
   restarts from it over the frames that followed it. If no frame after a key
   image shares enough points (a fast turn, a blank wall), the next frame
   becomes the key image: the path stays connected and the record says how few
   points it shares.
5. **Turns and distance.** A frame turned (odometric yaw) more than ``max_turn_deg``
   from the key image, or farther than ``max_spacing_m`` from it (odometric
   distance), cannot be the next one: it closes the segment as in rule 4. The
   repeat matches the next key image in a bounded window, and in a turn the
   points move out of it long before too few of them are tracked (the ``campus``
   U-turn, facing a bare end wall, had 34 corners and a 50 degree gap); facing
   distant landmarks, points stay tracked over metres, and the repeat's estimate
   far from its key image drifts (``building``'s yard). This adds to the paper's
   rule.
6. **The end.** :meth:`KeyImageSelector.finish` makes the last frame a key
   image (a path must end where the drive ended: another path may join there).

Distances are odometric: the sum of the straight steps between the odometry
poses of consecutive frames, from the first frame.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig, TeachConfig
from robot.vision.features import Features, GreyImage
from robot.vision.front_end import FrontEnd, make_front_end, stored_descriptors
from shared.camera_model import CameraModel
from shared.errors import InputError
from shared.memory import KeyframeRecord
from shared.pose import Pose2

TeachFrame = tuple[int, GreyImage, Pose2]
"""One frame of a teach recording: (t_ns, (H, W) uint8 grey image, pose in the drive's
odometry frame)."""


@dataclass(frozen=True, eq=False)
class SelectedKeyImage:
    """A key image chosen by the selector, ready for :meth:`VisualMemory.add_path`.

    Attributes:
        record: the key image (time, odometry, distance from the first frame,
            image, corners and descriptors, the corners tracked from the previous
            key image); the memory adds id and thumbnail.
        frame_index: position of its frame in the stream (0 = first frame).
        shared_points: tracked points it shares with the previous key image
            (``len(record.tracked_from_previous)``; 0 for the first key image);
            below the threshold only for a forced key image (rule 4) or the
            closing one (rule 5).
    """

    record: KeyframeRecord
    frame_index: int
    shared_points: int


@dataclass(frozen=True, eq=False)
class _Frame:
    index: int
    t_ns: int
    image: GreyImage
    odom_pose: Pose2
    distance_m: float
    features: Features


@dataclass(frozen=True, eq=False)
class _Seen:
    """A frame with the tracked points it shares with the key image.

    ``tracks``: (K, 2) int64 (key image corner, this frame's corner) of the points matched in it.
    """

    frame: _Frame
    tracks: npt.NDArray[np.int64]

    @property
    def shared(self) -> int:
        return len(self.tracks)


class _Tracks:
    """Points of one key image followed frame to frame (rule 1)."""

    def __init__(self, features: Features) -> None:
        self._live = features
        self._missed = np.zeros(len(features), dtype=np.intp)
        self._origin = np.arange(len(features), dtype=np.int64)  # the key image's corner

    @property
    def alive(self) -> int:
        return int(self._missed.shape[0])

    def update(self, features: Features, front_end: FrontEnd,
               config: TeachConfig) -> npt.NDArray[np.int64]:
        """Match the live points in a new frame.

        Returns:
            (K, 2) int64 (key image corner, frame corner) of the points matched.
        """
        matches = front_end.match(self._live, features, config.tracking)
        tracks = np.column_stack([self._origin[matches.idx_a], matches.idx_b]).astype(np.int64)
        moved = []
        for name in ("pixels_xy", "descriptors", "bearings"):
            column = np.array(getattr(self._live, name))
            column[matches.idx_a] = getattr(features, name)[matches.idx_b]
            moved.append(column)
        self._missed += 1
        self._missed[matches.idx_a] = 0
        keep = self._missed <= config.max_missed_frames
        pixels_xy, descriptors, bearings = (column[keep] for column in moved)
        self._live = Features(pixels_xy, descriptors, np.zeros(len(pixels_xy), np.float32),
                              bearings)
        self._missed = self._missed[keep]
        self._origin = self._origin[keep]
        return tracks


class KeyImageSelector:
    """Chooses key images from teach frames pushed one at a time (see the module rules).

    Pure: frames in, key images out; no clock, no I/O.

    Args:
        camera: the camera that takes the frames (image size, lens circle).
        features: the front end's method and parameters.
        config: M, the tracking window and the gap tolerance.
    """

    def __init__(self, camera: CameraModel, features: FeatureConfig, config: TeachConfig) -> None:
        self._camera = camera
        self._front_end = make_front_end(features, camera)
        self._config = config
        self._count = 0
        self._distance_m = 0.0
        self._last: _Frame | None = None
        self._last_seen: _Seen | None = None
        self._key: _Frame | None = None
        self._tracks: _Tracks | None = None  # from the first key image on
        self._threshold = config.min_tracked_points
        self._candidate: _Seen | None = None
        self._pending: list[_Seen] = []

    def push(
        self, t_ns: int, image: GreyImage, odom_pose: Pose2
    ) -> tuple[SelectedKeyImage, ...]:
        """Add the next frame.

        Args:
            t_ns: capture time, ns; strictly increasing.
            image: (H, W) uint8 grey frame of the camera's size.
            odom_pose: odometry pose at capture.

        Returns:
            The key images decided by this frame, in order (usually none; the
            first frame is always one).

        Raises:
            InputError: names the frame and the problem (size, dtype, time order,
                a non-finite pose).
        """
        frame = self._frame(t_ns, image, odom_pose)
        self._last = frame
        if self._key is None:
            self._last_seen = _Seen(frame, tracks=np.zeros((0, 2), dtype=np.int64))
            return (self._start_from(self._last_seen),)
        selected: list[SelectedKeyImage] = []
        queue = deque([frame])
        while queue:
            current = queue.popleft()
            assert self._tracks is not None  # set with the first key image
            tracks = self._tracks.update(current.features, self._front_end, self._config)
            m = self._threshold
            seen = self._last_seen = _Seen(current, tracks)
            if self._tracks.alive >= m and not self._too_far(current):
                if seen.shared >= m:
                    self._candidate, self._pending = seen, []
                else:
                    self._pending.append(seen)
                continue
            # Rules 4 and 5: too few points live, or turned or moved too far; close the
            # segment at the candidate, or at the first frame after the key image
            # if none shared M points.
            rest = [*self._pending, seen]
            key = self._candidate if self._candidate is not None else rest.pop(0)
            selected.append(self._start_from(key))
            queue.extendleft(p.frame for p in reversed(rest))
        return tuple(selected)

    def finish(self) -> tuple[SelectedKeyImage, ...]:
        """End the recording: the last frame becomes a key image unless it already is one.

        Returns:
            The closing key image, or nothing (no frames, or the last frame is a key image).
        """
        if self._last_seen is None or self._last_seen.frame is self._key:
            return ()
        return (self._start_from(self._last_seen),)

    def _too_far(self, frame: _Frame) -> bool:
        """Rule 5: ``frame`` is turned more than ``max_turn_deg`` from the key image, or
        farther than ``max_spacing_m`` from it."""
        assert self._key is not None
        turn = frame.odom_pose[2] - self._key.odom_pose[2]
        turn = math.atan2(math.sin(turn), math.cos(turn))
        return (abs(turn) > math.radians(self._config.max_turn_deg)
                or frame.distance_m - self._key.distance_m > self._config.max_spacing_m)

    def _start_from(self, seen: _Seen) -> SelectedKeyImage:
        """Make ``seen``'s frame the key image and restart tracking from its corners."""
        frame = seen.frame
        self._key = frame
        self._tracks = _Tracks(frame.features)
        fraction_of_corners = math.ceil(self._config.min_tracked_fraction * len(frame.features))
        self._threshold = max(1, min(self._config.min_tracked_points, fraction_of_corners))
        self._candidate, self._pending = None, []
        feats = frame.features
        record = KeyframeRecord(
            t_ns=frame.t_ns,
            odom_pose=frame.odom_pose,
            distance_m=frame.distance_m,
            image=frame.image,
            pixels_xy=np.array(feats.pixels_xy),
            patches=stored_descriptors(feats),
            tracked_from_previous=seen.tracks,
        )
        return SelectedKeyImage(record=record, frame_index=frame.index, shared_points=seen.shared)

    def _frame(self, t_ns: int, image: GreyImage, odom_pose: Pose2) -> _Frame:
        where = f"teach frame {self._count}"
        image = np.asarray(image)
        size = (self._camera.height, self._camera.width)
        if image.dtype != np.uint8 or image.shape != size:
            raise InputError(
                where,
                f"expected a {size[1]}x{size[0]} uint8 grey image, got shape {image.shape} "
                f"dtype {image.dtype}",
            )
        pose = tuple(float(v) for v in odom_pose)
        if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
            raise InputError(where, f"odom_pose must be 3 finite numbers, got {odom_pose!r}")
        if self._last is not None:
            if t_ns <= self._last.t_ns:
                raise InputError(
                    where, f"t_ns {t_ns} is not after the previous frame's {self._last.t_ns}"
                )
            x0, y0, _ = self._last.odom_pose
            self._distance_m += math.hypot(pose[0] - x0, pose[1] - y0)
        frame = _Frame(
            index=self._count,
            t_ns=int(t_ns),
            image=image,
            odom_pose=Pose2(*pose),
            distance_m=self._distance_m,
            features=self._front_end.describe(image),
        )
        self._count += 1
        return frame


def select_key_images(
    frames: Iterable[TeachFrame],
    camera: CameraModel,
    features: FeatureConfig,
    config: TeachConfig,
) -> list[SelectedKeyImage]:
    """Run a whole recording through a :class:`KeyImageSelector`.

    Args:
        frames: (t_ns, image, odom_pose) in capture order.
        camera: the camera that took them.
        features: the front end's method and parameters.
        config: key image selection parameters.

    Returns:
        The key images in driving order: the first frame, the chosen ones, the last frame.
    """
    selector = KeyImageSelector(camera, features, config)
    selected: list[SelectedKeyImage] = []
    for t_ns, image, odom_pose in frames:
        selected.extend(selector.push(t_ns, image, odom_pose))
    selected.extend(selector.finish())
    return selected
