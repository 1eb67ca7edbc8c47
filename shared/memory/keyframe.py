"""The records of a visual memory: key images, visual paths and junctions.

Courbon et al. (ICARCV 2008, sec. II-A): while a human guides the robot, key
images are stored in driving order; one taught drive is a *visual path*, a
weighted directed graph I_1 -> I_2 -> ... -> I_n. Visual paths join where a key
image of one is the same place as a key image of another (here a
:class:`Junction`), and together they form the visual memory
(:mod:`shared.memory.graph`).

Every record validates itself on construction and raises
:class:`~shared.errors.MemoryFormatError` naming the record and the field. The
array checks are public (:func:`check_grey_image`, :func:`check_features`) so
that the disk reader names the *file* at fault with the same rules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from numbers import Integral, Real
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from shared.errors import MemoryFormatError, ShapeError, check_shape
from shared.pose import Pose2

GreyImage = npt.NDArray[np.uint8]
"""(H, W) uint8 grey image."""
PixelsXY = npt.NDArray[np.float64]
"""(N, 2) float64 pixel coordinates (x right, y down; centre of the top-left pixel is (0, 0))."""
Patches = npt.NDArray[np.float32]
"""(N, P*P) float32 ZNCC descriptors, zero-mean and unit-norm rows (all zero if flat)."""
Tracks = npt.NDArray[np.int64]
"""(K, 2) int64 feature index pairs (previous key image's corner, this key image's corner)
of the points tracked from one key image to the next while teaching."""

THUMBNAIL_WIDTH_PX = 80
"""Width of every key image thumbnail, px."""
THUMBNAIL_HEIGHT_PX = 60
"""Height of every key image thumbnail, px."""


def thumbnail_from_image(image: GreyImage) -> GreyImage:
    """The key image thumbnail: the image shrunk to 80x60 by pixel-area averaging.

    The one definition used for key images and for the query images compared
    with them (global prefilter, ground station previews).

    Args:
        image: (H, W) uint8 grey image, any size.

    Returns:
        (60, 80) uint8 thumbnail (``cv2.INTER_AREA``: each output pixel is the mean
        of the input pixels it covers).
    """
    if not (isinstance(image, np.ndarray) and image.ndim == 2 and image.dtype == np.uint8
            and image.size > 0):
        raise ShapeError(
            f"image: expected a non-empty (H, W) uint8 grey image, got "
            f"{getattr(image, 'shape', type(image).__name__)} {getattr(image, 'dtype', '')}"
        )
    return cv2.resize(
        image, (THUMBNAIL_WIDTH_PX, THUMBNAIL_HEIGHT_PX), interpolation=cv2.INTER_AREA
    )


def check_grey_image(
    where: str, name: str, image: object, shape: tuple[int, int] | None = None
) -> None:
    """Fail unless ``image`` is a non-empty (H, W) uint8 array, of ``shape`` if given.

    Args:
        where: the file or record at fault, for the message.
        name: the field's name, for the message.
        image: the value to check.
        shape: the (H, W) wanted, or ``None`` for any size.

    Raises:
        MemoryFormatError: e.g. ``"key image 3: image: expected uint8 grey levels, got float32"``.
    """
    image = _checked_array(where, name, image, np.uint8, (None, None))
    if image.size == 0:
        raise MemoryFormatError(where, f"{name}: empty image, shape {image.shape}")
    if shape is not None and image.shape != shape:
        raise MemoryFormatError(
            where,
            f"{name}: expected {shape[1]}x{shape[0]} px, got {image.shape[1]}x{image.shape[0]} px",
        )


def check_features(
    where: str,
    pixels_xy: object,
    patches: object,
    width: int,
    height: int,
    descriptor_length: int | None = None,
) -> None:
    """Fail unless the corners and descriptors of one key image are consistent.

    Args:
        where: the file or record at fault, for the message.
        pixels_xy: should be (N, 2) float64, finite, inside a ``width`` x ``height``
            image (within half a pixel of the pixel centres).
        patches: should be (N, M) float32, finite, M >= 1.
        width: image width, px.
        height: image height, px.
        descriptor_length: the M wanted, or ``None`` for any.

    Raises:
        MemoryFormatError: naming the array and the problem.
    """
    pixels_xy = _checked_array(where, "pixels_xy", pixels_xy, np.float64, (None, 2))
    patches = _checked_array(where, "patches", patches, np.float32, (None, None))
    if patches.shape[1] == 0:
        raise MemoryFormatError(where, f"patches: descriptors are empty, shape {patches.shape}")
    if descriptor_length is not None and patches.shape[1] != descriptor_length:
        raise MemoryFormatError(
            where,
            f"patches: descriptors have {patches.shape[1]} values, the memory's have "
            f"{descriptor_length}",
        )
    if patches.shape[0] != pixels_xy.shape[0]:
        raise MemoryFormatError(
            where,
            f"{pixels_xy.shape[0]} corners in pixels_xy but {patches.shape[0]} rows in patches",
        )
    for name, array in (("pixels_xy", pixels_xy), ("patches", patches)):
        if not np.isfinite(array).all():
            raise MemoryFormatError(where, f"{name}: holds NaN or infinite values")
    x, y = pixels_xy[:, 0], pixels_xy[:, 1]
    inside = (x >= -0.5) & (x <= width - 0.5) & (y >= -0.5) & (y <= height - 0.5)
    outside = int(np.count_nonzero(~inside))
    if outside:
        raise MemoryFormatError(
            where, f"pixels_xy: {outside} corners lie outside the {width}x{height} image"
        )


def check_tracks(where: str, tracks: object, n_features: int) -> None:
    """Fail unless ``tracks`` pairs corners of the previous key image with this one's.

    Args:
        where: the file or record at fault, for the message.
        tracks: should be (K, 2) int64, indices >= 0, column 1 below ``n_features``,
            no index twice in a column (a corner is tracked at most once).
        n_features: N, the corners of the key image holding ``tracks``.

    Raises:
        MemoryFormatError: naming ``tracked_from_previous`` and the problem.
    """
    name = "tracked_from_previous"
    tracks = _checked_array(where, name, tracks, np.int64, (None, 2))
    if tracks.size and tracks.min() < 0:
        raise MemoryFormatError(where, f"{name}: holds a negative corner index")
    if tracks.size and tracks[:, 1].max() >= n_features:
        raise MemoryFormatError(
            where, f"{name}: corner {int(tracks[:, 1].max())} of this key image, which has "
            f"{n_features}"
        )
    for column, whose in ((0, "the previous key image's"), (1, "this key image's")):
        if np.unique(tracks[:, column]).size != tracks.shape[0]:
            raise MemoryFormatError(where, f"{name}: repeats a corner of {whose}")


def _no_tracks() -> Tracks:
    return np.zeros((0, 2), dtype=np.int64)


@dataclass(frozen=True, eq=False)
class KeyframeRecord:
    """A key image as teaching produces it, before the memory gives it an id.

    :meth:`VisualMemory.add_path <shared.memory.graph.VisualMemory.add_path>`
    turns a sequence of these into :class:`Keyframe` objects; it validates them
    then.

    Attributes:
        t_ns: capture time, ns, teach clock.
        odom_pose: teach odometry pose in the path's odometry frame.
        distance_m: odometric distance travelled since any fixed origin (e.g. the
            start of the recording), m; the memory stores it relative to the
            path's first key image.
        image: (H, W) uint8 grey key image, the camera's size.
        pixels_xy: (N, 2) float64 Harris corners, px.
        patches: (N, P*P) float32 ZNCC descriptors of those corners.
        tracked_from_previous: (K, 2) int64 corners tracked from the previous key
            image of the path to this one (:data:`Tracks`); empty for the first.
    """

    t_ns: int
    odom_pose: Pose2
    distance_m: float
    image: GreyImage
    pixels_xy: PixelsXY
    patches: Patches
    tracked_from_previous: Tracks = field(default_factory=_no_tracks)


@dataclass(frozen=True, eq=False)
class Keyframe:
    """One key image of the visual memory (a vertex of the multigraph).

    The arrays are copied on construction and read-only.

    Attributes:
        id: unique in the memory, >= 0; never reused.
        path_id: the visual path it was taught on.
        index: its position along that path (0, 1, 2, ...).
        t_ns: capture time, ns, teach clock.
        odom_pose: teach odometry pose in the path's odometry frame.
        distance_m: odometric distance from the path's first key image, m, >= 0.
        image: (H, W) uint8 grey key image.
        pixels_xy: (N, 2) float64 Harris corners, px, inside the image.
        patches: (N, P*P) float32 ZNCC descriptors (zero-mean, unit-norm rows).
        thumbnail: (60, 80) uint8, :func:`thumbnail_from_image` of the image.
        tracked_from_previous: (K, 2) int64 pairs (corner of the previous key image of
            the path, corner of this one) tracked while teaching (:data:`Tracks`);
            empty for a path's first key image, or when the teach did not record them.

    Raises:
        MemoryFormatError: a field is missing its type, range or shape; names
            ``key image <id>`` and the field.
    """

    id: int
    path_id: int
    index: int
    t_ns: int
    odom_pose: Pose2
    distance_m: float
    image: GreyImage
    pixels_xy: PixelsXY
    patches: Patches
    thumbnail: GreyImage
    tracked_from_previous: Tracks = field(default_factory=_no_tracks)

    def __post_init__(self) -> None:
        where = f"key image {self.id}"
        for name in ("id", "path_id", "index"):
            object.__setattr__(self, name, _non_negative_int(where, name, getattr(self, name)))
        if not isinstance(self.t_ns, Integral) or isinstance(self.t_ns, bool):
            raise MemoryFormatError(where, f"t_ns: expected an integer, got {self.t_ns!r}")
        object.__setattr__(self, "t_ns", int(self.t_ns))
        pose = tuple(self.odom_pose) if isinstance(self.odom_pose, tuple | list) else ()
        if len(pose) != 3:
            raise MemoryFormatError(
                where, f"odom_pose: expected (x_m, y_m, yaw_rad), got {self.odom_pose!r}"
            )
        object.__setattr__(
            self, "odom_pose", Pose2(*(_finite(where, "odom_pose", v) for v in pose))
        )
        distance_m = _finite(where, "distance_m", self.distance_m)
        if distance_m < 0.0:
            raise MemoryFormatError(where, f"distance_m: must be >= 0 m, got {distance_m} m")
        object.__setattr__(self, "distance_m", distance_m)

        check_grey_image(where, "image", self.image)
        height, width = self.image.shape
        check_features(where, self.pixels_xy, self.patches, width, height)
        check_grey_image(
            where, "thumbnail", self.thumbnail, (THUMBNAIL_HEIGHT_PX, THUMBNAIL_WIDTH_PX)
        )
        check_tracks(where, self.tracked_from_previous, self.pixels_xy.shape[0])
        for name in ("image", "pixels_xy", "patches", "thumbnail", "tracked_from_previous"):
            array = np.array(getattr(self, name), copy=True)
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    @property
    def n_features(self) -> int:
        """Number of corners N."""
        return int(self.pixels_xy.shape[0])

    @property
    def descriptor_length(self) -> int:
        """Length P*P of one ZNCC descriptor."""
        return int(self.patches.shape[1])


@dataclass(frozen=True)
class VisualPath:
    """One taught drive: key image ids in driving order.

    Consecutive ids are directed edges of the multigraph (a path is followed in
    the direction it was taught: its key images look forward).

    Attributes:
        id: unique in the memory, >= 0.
        name: what was taught, e.g. the route name; one line, non-empty.
        keyframe_ids: at least one id, no repeats; ``keyframe_ids[i]`` has index i.

    Raises:
        MemoryFormatError: names ``path <id>`` and the field.
    """

    id: int
    name: str
    keyframe_ids: tuple[int, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "id", _non_negative_int(f"path {self.id}", "id", self.id))
        where = f"path {self.id}"
        if not isinstance(self.name, str) or not self.name.strip() or "\n" in self.name:
            raise MemoryFormatError(where, f"name: expected a non-empty line, got {self.name!r}")
        if not isinstance(self.keyframe_ids, tuple | list) or not self.keyframe_ids:
            raise MemoryFormatError(
                where, f"keyframe_ids: expected at least one id, got {self.keyframe_ids!r}"
            )
        ids = tuple(_non_negative_int(where, "keyframe_ids", i) for i in self.keyframe_ids)
        if len(set(ids)) != len(ids):
            repeated = next(i for i in ids if ids.count(i) > 1)
            raise MemoryFormatError(where, f"keyframe_ids: key image {repeated} appears twice")
        object.__setattr__(self, "keyframe_ids", ids)


@dataclass(frozen=True)
class Junction:
    """Two key images that are the same place: a two-way, zero-length link.

    Typically the first or last key image of a new path, localized as key image
    ``to_id`` of a path already in the memory.

    Attributes:
        from_id: a key image, e.g. the last of path A.
        to_id: the key image it was localized as, e.g. in path B; differs from ``from_id``.
        matches: the number of point matches that established it, >= 0.

    Raises:
        MemoryFormatError: names the junction and the field.
    """

    from_id: int
    to_id: int
    matches: int

    def __post_init__(self) -> None:
        where = f"junction {self.from_id} -> {self.to_id}"
        for name in ("from_id", "to_id", "matches"):
            object.__setattr__(self, name, _non_negative_int(where, name, getattr(self, name)))
        if self.from_id == self.to_id:
            raise MemoryFormatError(where, "joins a key image to itself")

    @property
    def pair(self) -> frozenset[int]:
        """The two key image ids, unordered (a junction is traversable both ways)."""
        return frozenset((self.from_id, self.to_id))


def _checked_array(
    where: str, name: str, array: object, dtype: type[np.generic], shape: tuple[int | None, ...]
) -> npt.NDArray[Any]:
    """``array`` itself, once known to be an ndarray of ``dtype`` and ``shape``."""
    if not isinstance(array, np.ndarray):
        raise MemoryFormatError(
            where, f"{name}: expected a numpy array, got {type(array).__name__}"
        )
    try:
        check_shape(name, array.shape, shape)
    except ShapeError as e:
        raise MemoryFormatError(where, str(e)) from None
    if array.dtype != dtype:
        raise MemoryFormatError(
            where, f"{name}: expected dtype {np.dtype(dtype).name}, got {array.dtype.name}"
        )
    return array


def _non_negative_int(where: str, name: str, value: Any) -> int:
    if not isinstance(value, Integral) or isinstance(value, bool) or value < 0:
        raise MemoryFormatError(where, f"{name}: expected an integer >= 0, got {value!r}")
    return int(value)


def _finite(where: str, name: str, value: Any) -> float:
    if not isinstance(value, Real) or isinstance(value, bool) or not math.isfinite(value):
        raise MemoryFormatError(where, f"{name}: expected a finite number, got {value!r}")
    return float(value)
