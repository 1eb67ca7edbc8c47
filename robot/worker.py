"""The runtime's worker: disk reads, photo localization and memory writes off the loop thread.

Theory of operation
-------------------

The loop thread must keep its frame rate: it never reads a photo from disk, decodes
it, localizes it in the memory, or joins and writes a taught path. It hands such a
job to :class:`Worker` (one thread, so jobs run one after the other in the order
given: a second taught path is joined to the memory the first one wrote) with
immutable inputs (a path, a memory that is never changed in place, the key image
records), and takes the job's result, an event of :mod:`robot.modes`, back on a
later frame (:meth:`Worker.results`, called at the start of each loop call).

In lock-step (the simulator's clock: the demo, tests) the outcome must not depend on
how fast the worker's thread runs: a ``lockstep`` worker's results are waited for
at the next loop call, so each result lands exactly one frame after its job was
given, on every run. The real robot does not wait: a result lands on the first frame
after the job finished.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import ParamSpec

from robot.config import VmnavConfig
from robot.memory.junctions import join_path
from robot.memory.localize import Localizer
from robot.mode_events import Event, PathNotStored, PathStored, PhotoFound, PhotoNotFound
from robot.vision.front_end import front_end_label
from shared.camera_model import CameraModel
from shared.errors import InputError, VmnavError
from shared.image_decode import photo_pixel_limit, read_grey
from shared.memory import KeyframeRecord, VisualMemory, read_memory, write_memory
from shared.memory.store import check_no_orphans

_P = ParamSpec("_P")


class Worker:
    """One thread for the runtime's slow jobs (module docstring).

    Args:
        lockstep: wait for each result at the next :meth:`results` (deterministic
            frames); otherwise take only the results that are ready.
    """

    def __init__(self, lockstep: bool) -> None:
        self._lockstep = lockstep
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="robot-worker")
        self._futures: deque[Future[Event]] = deque()

    def submit(self, job: Callable[_P, Event], *args: _P.args, **kwargs: _P.kwargs) -> None:
        """Run ``job(*args, **kwargs)`` on the worker's thread."""
        self._futures.append(self._executor.submit(job, *args, **kwargs))

    def results(self) -> list[Event]:
        """The results of the jobs done, in the order given (all of them in lock-step).

        Raises:
            Exception: whatever a job raised (a bug: jobs return expected failures as
                events).
        """
        out: list[Event] = []
        while self._futures and (self._lockstep or self._futures[0].done()):
            out.append(self._futures.popleft().result())
        return out

    def close(self) -> None:
        """Finish the job in progress, drop the others and their results; idempotent."""
        self._executor.shutdown(wait=True, cancel_futures=True)
        self._futures.clear()


def find_photo(path: Path, localizer: Localizer, camera: CameraModel) -> Event:
    """Read the photo at ``path`` and find it among the key images of ``localizer``.

    The photo came from outside (an FTP upload): its header is checked before it is
    decoded, with a budget of a few times the camera's pixels
    (:func:`shared.image_decode.read_grey`), so a forged file costs neither memory nor
    time here.

    Args:
        path: a PNG or JPEG file, read as grey.
        localizer: over the memory in force (read only).
        camera: the memory's camera; the photo must have its size.

    Returns:
        :class:`PhotoFound`, or :class:`PhotoNotFound` saying why (unreadable or
        refused, another size than the camera's, not in the memory).
    """
    try:
        photo = read_grey(path, photo_pixel_limit(camera.width, camera.height))
    except InputError as e:
        return PhotoNotFound(logging.ERROR, f"photo {path.name}: {e.problem}")
    if photo.shape != (camera.height, camera.width):
        return PhotoNotFound(logging.ERROR,
                             f"photo {path.name}: {photo.shape[1]}x{photo.shape[0]} px, the "
                             f"camera's images are {camera.width}x{camera.height}")
    found = localizer.localize(photo)
    if not found.ok or found.keyframe_id is None:
        return PhotoNotFound(logging.WARNING,
                             f"photo {path.name}: not in the memory (best {found.detail})")
    return PhotoFound(found.keyframe_id, f"photo {path.name}: {found.detail}, going there")


def store_path(memory_dir: Path, camera: CameraModel, name: str,
               records: Sequence[KeyframeRecord], config: VmnavConfig) -> Event:
    """Add a taught path to the memory in ``memory_dir``, joined to the others, and write it.

    The memory is read again from the folder (an empty one when the folder holds none),
    so the memory in force is never changed in place.

    Args:
        memory_dir: the memory's folder.
        camera: the camera of a new memory.
        name: the path's name.
        records: its key images in driving order.
        config: teaching (minimum length), features and localization settings.

    Returns:
        :class:`PathStored` with the new memory, or :class:`PathNotStored` (too short,
        or the folder not writable or holding files the memory does not own).
    """
    teach = config.teach
    length_m = records[-1].distance_m if records else 0.0
    if len(records) < 2 or length_m < teach.min_path_length_m:
        return PathNotStored(f"teach {name!r}: {length_m:.2f} m driven, a path needs "
                             f"{teach.min_path_length_m:.2f} m: nothing stored")
    try:
        check_no_orphans(memory_dir)
        memory = (read_memory(memory_dir) if (memory_dir / "manifest.json").exists()
                  else VisualMemory(camera))
        path = memory.add_path(name, list(records), front_end_label(config.features, camera))
        attempts = join_path(memory, path, config.camera.mount, config.features,
                             config.localize, teach)
        write_memory(memory_dir, memory)
    except (VmnavError, OSError) as e:
        return PathNotStored(f"teach {name!r} not stored: {e}")
    joined = sum(a.accepted for a in attempts)
    localizer = Localizer.from_memory(memory, config.camera.mount, config.features,
                                      config.localize)
    return PathStored(memory, localizer, path.id,
                      f"path {path.id} {name!r}: {len(records)} key images, "
                      f"{joined} junction(s)")
