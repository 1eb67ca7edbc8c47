"""``vmnav memory build LOG.mcap --memory DIR``: a visual path from a recorded teach drive.

This is how a real robot's teach run becomes a memory (``vmnav teach --sim --log``
records the same kind of log). The log is one file, several files, or the first file
of a rotated series (``teach-x-0001.mcap`` stands for ``-0002``, ... of the same run),
put in time order by :func:`shared.logs.series.log_series` (overlaps and gaps are
errors). Together its files need two topics:

* :data:`~shared.logs.topics.CAMERA_IMAGE`: ``foxglove.CompressedImage`` frames (JPEG,
  or anything ``cv2.imdecode`` reads), decoded to grey; each must be of the memory
  camera's size;
* :data:`~shared.logs.topics.TF`: ``foxglove.FrameTransforms`` holding the wheel
  odometry ``odom`` -> ``base_link`` (other transforms are ignored).

Each frame gets the odometry pose at its log time: the pose logged at that time, else
the linear interpolation between the poses just before and just after it (yaw the
short way round). Frames before the first or after the last odometry pose have no
pose and are left out (counted). The frames then go through
:func:`robot.teach.select_key_images` as in ``vmnav teach --sim``; the key images
become a new path of the memory in DIR (a new memory with ``--camera``'s or the
default camera if DIR holds none), joined to its other paths by
:func:`robot.memory.junctions.join_path`, and :func:`shared.memory.write_memory` stores it
(manifest last, so an interrupted write leaves the memory as it was). Bad input (not
MCAP, no frames, no odometry, a frame of the wrong size) is found before anything is
written, and so is a folder that :func:`shared.memory.open_or_create` refuses (files
without a manifest, a memory of another camera than ``--camera``'s).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from shared.errors import InputError
from shared.logs import topics
from shared.logs.series import log_series, series_name
from shared.pose import Pose2

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from robot.memory.junctions import JunctionAttempt
    from robot.teach import SelectedKeyImage, TeachFrame
    from shared.camera_model import CameraModel
    from shared.memory import VisualMemory, VisualPath


@dataclass(frozen=True, eq=False)
class Odometry:
    """The odometry poses of a log, in time order.

    Attributes:
        t_ns: (N,) int64 log times, strictly increasing, ns.
        x_m, y_m: (N,) float64 position of ``base_link`` in ``odom``, m.
        yaw_rad: (N,) float64 heading, unwrapped (no jumps of more than pi), rad.
    """

    t_ns: npt.NDArray[np.int64]
    x_m: npt.NDArray[np.float64]
    y_m: npt.NDArray[np.float64]
    yaw_rad: npt.NDArray[np.float64]

    def pose_at(self, t_ns: int) -> Pose2 | None:
        """The pose at ``t_ns``, interpolated linearly; None outside the logged span."""
        if not self.t_ns[0] <= t_ns <= self.t_ns[-1]:
            return None
        x, y, yaw = (float(np.interp(t_ns, self.t_ns, v)) for v in (self.x_m, self.y_m,
                                                                       self.yaw_rad))
        return Pose2(x, y, math.atan2(math.sin(yaw), math.cos(yaw)))


@dataclass(frozen=True, eq=False)
class BuiltPath:
    """What :func:`build_path` did.

    Attributes:
        path: the new path.
        files: the log's files, in time order.
        key_images: its key images as selected, in driving order.
        frames: camera frames given to the selector.
        without_odometry: camera frames left out (outside the odometry's span).
        attempts: the junction attempts of its ends (accepted or not).
    """

    path: VisualPath
    files: tuple[Path, ...]
    key_images: tuple[SelectedKeyImage, ...]
    frames: int
    without_odometry: int
    attempts: tuple[JunctionAttempt, ...]


def yaw_from_quaternion(w: float, x: float, y: float, z: float) -> float:
    """Heading (rotation about z) of a unit quaternion, rad in [-pi, pi] (ZYX Euler yaw)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def check_log_topics(files: Sequence[Path]) -> None:
    """Check that the log's MCAP ``files`` hold camera frames and transforms between them.

    Raises:
        InputError: naming the log: a file missing or not MCAP, or no message on one
            of the topics.
    """
    from shared.logs.reader import log_info

    counts: dict[str, int] = {}
    for file in files:
        for t in log_info(file).topics:
            counts[t.topic] = counts.get(t.topic, 0) + t.message_count
    for topic, what in ((topics.CAMERA_IMAGE, "camera frames"), (topics.TF, "odometry")):
        if not counts.get(topic):
            raise InputError(series_name(files), f"no {what} (no messages on {topic}); a teach "
                             f"log needs "
                             f"camera frames on {topics.CAMERA_IMAGE} and the odometry "
                             f"{topics.FRAME_ODOM} -> {topics.FRAME_BASE} on {topics.TF}")


def read_odometry(files: Sequence[Path]) -> Odometry:
    """The ``odom`` -> ``base_link`` transforms of the log's ``files`` (the last one where
    times repeat).

    Raises:
        InputError: naming the file: unreadable, or naming the log: no such transform.
    """
    from shared.logs.reader import read_messages

    poses: dict[int, Pose2] = {}
    for file in files:
        for message in read_messages(file, [topics.TF]):
            for tf in message.data.get("transforms", []):
                if (tf.get("parent_frame_id"), tf.get("child_frame_id")) != (topics.FRAME_ODOM,
                                                                             topics.FRAME_BASE):
                    continue
                try:
                    p, q = tf["translation"], tf["rotation"]
                    poses[message.clock_ns] = Pose2(
                        float(p["x"]), float(p["y"]),
                        yaw_from_quaternion(float(q["w"]), float(q["x"]), float(q["y"]),
                                            float(q["z"])))
                except (KeyError, TypeError, ValueError) as e:
                    raise InputError(file, f"{topics.TF} at {message.clock_ns} ns: malformed "
                                     f"transform ({e!r})") from None
    if not poses:
        raise InputError(series_name(files), f"no odometry: no {topics.FRAME_ODOM} -> "
                         f"{topics.FRAME_BASE} transform on {topics.TF}")
    times = sorted(poses)
    x, y, yaw = (np.array([poses[t][i] for t in times]) for i in range(3))
    return Odometry(np.array(times, dtype=np.int64), x, y, np.unwrap(yaw))


class LogFrames:
    """The camera frames of a log with their odometry poses, decoded one at a time.

    Iterate once; afterwards :attr:`frames` and :attr:`without_odometry` count them.

    Args:
        files: the log's MCAP files, in time order.
        camera: the camera the frames must fit (width x height).
        odometry: the log's odometry.
    """

    def __init__(self, files: Sequence[Path], camera: CameraModel, odometry: Odometry) -> None:
        self._files = tuple(files)
        self._size = (camera.height, camera.width)
        self._odometry = odometry
        self.frames = 0
        self.without_odometry = 0

    def __iter__(self) -> Iterator[TeachFrame]:
        from shared.logs.messages import image_from_compressed
        from shared.logs.reader import read_messages

        for file in self._files:
            for message in read_messages(file, [topics.CAMERA_IMAGE]):
                t_ns = message.clock_ns
                pose = self._odometry.pose_at(t_ns)
                if pose is None:
                    self.without_odometry += 1
                    continue
                where = f"{file}: camera frame at {t_ns} ns"
                try:
                    image, _ = image_from_compressed(message.data)
                except ValueError as e:
                    raise InputError(where, str(e)) from None
                if image.shape != self._size:
                    raise InputError(where, f"is {image.shape[1]}x{image.shape[0]} px; the "
                                     f"memory's camera takes {self._size[1]}x{self._size[0]} px")
                self.frames += 1
                yield t_ns, image, pose


def build_path(logs: Sequence[Path], directory: Path, name: str, camera_file: str | None,
               config: VmnavConfig) -> tuple[BuiltPath, VisualMemory]:
    """Select key images from the teach drive in ``logs`` and add them to the memory.

    Args:
        logs: the teach log: one MCAP file, several, or the first of a rotated series.
        directory: the memory's folder (created if needed).
        name: the new path's name.
        camera_file: calibration JSON; a new memory gets its camera, a stored one must
            have it. None: a stored memory's own camera, the default camera for a new one.
        config: feature, teach, localization parameters.

    Returns:
        What was built, and the memory as written.

    Raises:
        InputError: bad input (see the module docstring), or a folder that
            :func:`shared.memory.open_or_create` refuses; the memory is not written.
        MemoryFormatError: see :func:`shared.memory.open_or_create`.
        CalibrationError: a bad camera file.
    """
    from robot.memory.junctions import join_path
    from robot.teach import select_key_images
    from robot.vision.front_end import front_end_label
    from shared.calibration import read_camera
    from shared.memory import open_or_create, write_memory

    files = log_series(logs)
    check_log_topics(files)
    odometry = read_odometry(files)
    memory = open_or_create(directory, None if camera_file is None else read_camera(camera_file))
    frames = LogFrames(files, memory.camera, odometry)
    key_images = select_key_images(frames, memory.camera, config.features, config.teach)
    if not key_images:
        raise InputError(series_name(files), f"no camera frame lies within the odometry's span "
                         f"({frames.without_odometry} frames without a pose)")
    path = memory.add_path(name, [k.record for k in key_images],
                           front_end_label(config.features, memory.camera))
    attempts = join_path(memory, path, config.camera.mount, config.features, config.localize,
                  config.teach)
    write_memory(directory, memory)
    return BuiltPath(path, files, tuple(key_images), frames.frames, frames.without_odometry,
                     tuple(attempts)), memory


def summary_text(built: BuiltPath, memory: VisualMemory, directory: Path) -> str:
    """What ``vmnav memory build`` prints: the new path, its junctions, the memory."""
    from robot.memory.junctions import junction_lines

    log = series_name(built.files)
    path = built.path
    length_m = memory.keyframes[path.keyframe_ids[-1]].distance_m
    skipped = (f" ({built.without_odometry} frames outside the odometry left out)"
               if built.without_odometry else "")
    lines = [
        f"built path {path.id} {path.name!r} from {log}: {len(path.keyframe_ids)} key images "
        f"(ids {path.keyframe_ids[0]}-{path.keyframe_ids[-1]}) from {built.frames} frames "
        f"over {length_m:.2f} m of odometry{skipped}",
        *junction_lines(built.attempts, memory, directory),
    ]
    return "\n".join(lines)
