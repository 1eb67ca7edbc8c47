"""The robot's camera: a :class:`shared.interfaces.FrameSource` over ``cv2.VideoCapture``.

The source is a device index (``"0"``), a video file, or a URL (an MJPEG stream over
HTTP such as ``vmnav sim serve --video``'s, RTSP, ...), as ``CameraSourceConfig.source``
says.

Rules:

1. **Opening** happens in the constructor and fails with one clear line: a missing
   file (:class:`InputError`), a source that does not open or gives no first frame
   in time (:class:`TransportError`, bounded by ``open_timeout_ns`` and
   ``read_timeout_ns`` for a URL), frames of another size than the camera
   calibration's (:class:`InputError` naming both sizes).
2. **A reader thread** reads continuously. A live source (device, URL) keeps only the
   newest frame: a slow consumer gets the latest image, never a backlog. A file is
   read one frame per frame consumed (none is dropped). Each frame is stamped on the
   injected clock when it arrives and converted to (H, W) uint8 grey.
3. **Bad input.** A failed read is an undecodable frame and is skipped; a frame of
   another size is dropped and counted. ``max_failed_reads`` failures in a row mean
   the source is gone: a file has ended; a live source is released and reopened
   after a backoff (``reconnect_initial_ns``, doubling to ``reconnect_max_ns``,
   reset by a frame), forever, in the reader thread.
4. **Reading.** :meth:`VideoCaptureSource.read` (the FrameSource) waits for a frame
   newer than the last one returned, however long; :meth:`VideoCaptureSource.read_within`
   waits at most a timeout and returns a :class:`FrameStall` when none came, so the
   robot's loop can stop the base and carry on once frames return. Both return None
   once no frame will come again (a file ended, or :meth:`close`). Waits are real
   time (they wait on the reader thread); stamps are on the clock.
5. :meth:`VideoCaptureSource.close` stops and joins the reader thread; a read blocked
   in OpenCV on a silent stream finishes first (at most ``read_timeout_ns``).
"""

from __future__ import annotations

import dataclasses
import logging
import threading
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import CameraSourceConfig
from shared.camera_model import CameraModel
from shared.clock import Clock
from shared.errors import InputError, TransportError

log = logging.getLogger(__name__)

Frame = tuple[int, npt.NDArray[np.uint8]]
"""``(t_ns, image)``: arrival time on the clock, ns, and the (H, W) uint8 grey image."""


@dataclass(frozen=True, slots=True)
class FrameStall:
    """No new frame within a :meth:`VideoCaptureSource.read_within` wait; frames may return.

    Attributes:
        t_ns: when the wait ended, on the source's clock, ns.
        last_frame_ns: arrival time of the newest frame the source has had, ns (the
            stall has lasted ``t_ns - last_frame_ns``).
    """

    t_ns: int
    last_frame_ns: int


@dataclass(frozen=True, slots=True)
class CameraSourceStats:
    """Counts of a :class:`VideoCaptureSource` since it opened.

    Attributes:
        frames: frames accepted (the right size).
        skipped: accepted frames replaced by a newer one before anybody read them.
        failed_reads: reads that gave no frame (undecodable frames, a source going away).
        wrong_size: frames dropped for not having the calibration's size.
        reopens: times a lost live source was opened again.
    """

    frames: int = 0
    skipped: int = 0
    failed_reads: int = 0
    wrong_size: int = 0
    reopens: int = 0


class VideoCaptureSource:
    """Grey frames from ``cv2.VideoCapture(config.source)`` (see the module rules).

    Args:
        config: the source and its timeouts and backoff.
        clock: stamps the frames.
        camera: the calibration; frames must have its image size (None: any size,
            the first frame's).

    Raises:
        InputError: the source is a file that does not exist, or its frames are not
            the calibration's size.
        TransportError: the source does not open, or gives no frame in time.
    """

    def __init__(self, config: CameraSourceConfig, clock: Clock,
                 camera: CameraModel | None = None) -> None:
        self.config = config
        self._clock = clock
        self._source: int | str = int(config.source) if config.source.isdigit() else config.source
        self._is_url = "://" in config.source
        self._live = self._is_url or isinstance(self._source, int)
        if not self._live and not Path(config.source).is_file():
            raise InputError(config.source, "no such video file (nor a device index or URL)")
        capture = self._open()
        if capture is None:
            raise TransportError(config.source, f"cannot open with OpenCV ({self._cannot_why()})")
        ok, image = capture.read()
        t_ns = clock.now_ns()
        if not ok:
            capture.release()
            raise TransportError(config.source, "opened, but gave no frame" + (
                f" within {config.read_timeout_ns / 1e9:g} s" if self._is_url else ""))
        grey = _grey(image)
        height, width = grey.shape
        if camera is not None and (camera.width, camera.height) != (width, height):
            capture.release()
            raise InputError(config.source, f"frames are {width}x{height} px, the camera "
                             f"calibration's are {camera.width}x{camera.height} px")
        self.size_wh = (width, height)
        """Width and height of every frame delivered, px."""
        self._changed = threading.Condition()
        self._newest: Frame = (t_ns, grey)
        self._seq = 1  # of the newest frame; the last one returned is self._read_seq
        self._read_seq = 0
        self._ended = False  # the reader thread has finished
        self._closed = False
        self._stats = CameraSourceStats(frames=1)
        self._size_ok = True  # the last frame read had the right size (reader thread only)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(capture,),
                                        name=f"camera {config.source}")
        self._thread.start()

    def __enter__(self) -> VideoCaptureSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- reading (rule 4) ---------------------------------------------------------------

    def read(self) -> Frame | None:
        """The next frame newer than the last one returned, waiting as long as it takes.

        Returns:
            ``(t_ns, image)``: arrival time on the clock, ns, and the (H, W) uint8 grey
            image; None when no frame will come (a file ended, the source closed).
        """
        with self._changed:
            self._changed.wait_for(self._has_news)
            return self._take()

    def read_within(self, timeout_ns: int) -> Frame | FrameStall | None:
        """Like :meth:`read`, but waiting at most ``timeout_ns`` (real time).

        Returns:
            a frame as :meth:`read`; a :class:`FrameStall` when no new frame came in
            ``timeout_ns`` (the source may still resume: call again); None when no
            frame will come.
        """
        with self._changed:
            if not self._changed.wait_for(self._has_news, timeout_ns / 1e9):
                return FrameStall(self._clock.now_ns(), self._newest[0])
            return self._take()

    def stats(self) -> CameraSourceStats:
        """The counts so far."""
        with self._changed:
            return self._stats

    def close(self) -> None:
        """Stop reading and release the source (rule 5); idempotent."""
        self._stop.set()
        with self._changed:
            self._closed = True
            self._changed.notify_all()
        self._thread.join()

    def _has_news(self) -> bool:
        return self._closed or self._ended or self._seq > self._read_seq

    def _take(self) -> Frame | None:
        if self._closed or self._seq == self._read_seq:  # the newest one was returned
            return None
        self._read_seq = self._seq
        self._changed.notify_all()  # a file's reader waits for this
        return self._newest

    # -- the reader thread (rules 2 and 3) ----------------------------------------------

    def _run(self, capture: cv2.VideoCapture | None) -> None:
        failures = 0  # failed reads in a row
        reopen_wait_ns = self.config.reconnect_initial_ns
        try:
            while not self._stop.is_set():
                if capture is None:
                    if self._stop.wait(reopen_wait_ns / 1e9):
                        break
                    capture = self._open()
                    if capture is None:
                        reopen_wait_ns = min(2 * reopen_wait_ns, self.config.reconnect_max_ns)
                        log.debug("camera %s: cannot reopen yet", self.config.source)
                    else:
                        self._count(reopens=1)
                        log.info("camera %s: reopened", self.config.source)
                    continue
                ok, image = capture.read()
                if ok:
                    failures = 0
                    reopen_wait_ns = self.config.reconnect_initial_ns
                    self._deliver(self._clock.now_ns(), _grey(image))
                    continue
                failures += 1
                self._count(failed_reads=1)
                if failures < self.config.max_failed_reads:
                    continue
                capture.release()
                capture, failures = None, 0
                if not self._live:
                    break
                log.warning("camera %s: lost (%d failed reads in a row); reopening",
                            self.config.source, self.config.max_failed_reads)
        finally:
            if capture is not None:
                capture.release()
            with self._changed:
                self._ended = True
                self._changed.notify_all()

    def _deliver(self, t_ns: int, grey: npt.NDArray[np.uint8]) -> None:
        height, width = grey.shape
        if (width, height) != self.size_wh:
            self._count(wrong_size=1)
            if self._size_ok:  # once per run of such frames
                log.warning("camera %s: dropping %dx%d frames (expected %dx%d)",
                            self.config.source, width, height, *self.size_wh)
            self._size_ok = False
            return
        self._size_ok = True
        with self._changed:
            if not self._live:  # a file waits until its previous frame was read
                self._changed.wait_for(lambda: self._seq == self._read_seq or self._closed)
                if self._closed:
                    return
            skipped = int(self._seq > self._read_seq)
            self._newest = (t_ns, grey)
            self._seq += 1
            self._stats = _add(self._stats, frames=1, skipped=skipped)
            self._changed.notify_all()

    def _count(self, **deltas: int) -> None:
        with self._changed:
            self._stats = _add(self._stats, **deltas)

    # -- opening --------------------------------------------------------------------------

    def _open(self) -> cv2.VideoCapture | None:
        """The source opened, or None; a URL within the configured timeouts."""
        if self._is_url:
            capture = cv2.VideoCapture(self._source, cv2.CAP_FFMPEG, [
                cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, self.config.open_timeout_ns // 1_000_000,
                cv2.CAP_PROP_READ_TIMEOUT_MSEC, self.config.read_timeout_ns // 1_000_000,
            ])
        else:
            capture = cv2.VideoCapture(self._source)
        if capture.isOpened():
            return capture
        capture.release()
        return None

    def _cannot_why(self) -> str:
        if isinstance(self._source, int):
            return f"no camera device {self._source}, or it is busy"
        if self._is_url:
            return (f"not found, refused, or nothing within "
                    f"{self.config.open_timeout_ns / 1e9:g} s")
        return "not a video file OpenCV can decode"


def _grey(image: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """(H, W) uint8 grey from what VideoCapture decodes: BGR, BGRA or already grey."""
    if image.ndim == 2:
        return image
    if image.shape[2] == 4:
        return cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def _add(stats: CameraSourceStats, **deltas: int) -> CameraSourceStats:
    return dataclasses.replace(stats, **{name: getattr(stats, name) + delta
                                         for name, delta in deltas.items()})
