"""``LogWriter``: field logging to MCAP off the control loop.

Theory of operation. The loop calls ``log_*``; each call checks its arguments,
copies what the caller might reuse (an image, a dict) and puts one job on a
bounded queue, never waiting: when the queue is full the job is dropped and
counted. One writer thread takes jobs, builds the messages (JPEG encoding, JSON)
and writes them through :class:`~shared.logs._mcap_files.McapFiles`, which owns the
files, rotates them and swallows OS errors (reported once, counted). The thread
flushes the open chunk at most ``flush_period_ns`` (wall time) after the first
message written since the last flush, so a ``kill -9`` loses at most that plus what
waited in the queue; ``close()`` (also run at interpreter exit) finishes the file
with its summary and index. Entry points turn SIGTERM into ``sys.exit`` so that
exit runs too (mcap-logging.md §1 "Exit paths").

Quota (``LogConfig.max_bytes``): once the files hold that much, the writer thread stops
writing the bulky topics (camera frames, annotations, MAVLink) and says so once, as a
WARNING on the console and a ``foxglove.Log`` line in the file; the loop's calls for
them are then refused at once (``False``, counted in ``over_quota``). The rest goes on.

Time: ``t_ns`` is the data's time from the loop's clock (time since boot, or simulated
time), integer ns >= 0; it stays as it is in our JSON messages (``stamp_ns``), which is
what control and replay read. The MCAP ``log_time`` and ``publish_time`` and the Foxglove
``timestamp`` fields are Unix time, ``t_ns + unix_offset_ns``: the entry point measures
the offset once when it opens the log (:func:`shared.clock.unix_offset_ns`); a lock-step
simulation puts its clock's zero at the wall time the run started. The offset is in
every file's metadata (``_mcap_files`` rule 5). Only the flush and retry periods use the
wall clock, in the writer thread.
"""

from __future__ import annotations

import atexit
import logging
import queue
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import cv2
import numpy as np
import numpy.typing as npt

from shared.clock import NS_PER_S, WallClock
from shared.config import LogConfig
from shared.errors import check_shape
from shared.logs import messages, topics
from shared.logs._mcap_files import McapFiles, Record
from shared.logs.schemas import (
    COMPRESSED_IMAGE,
    FRAME_TRANSFORMS,
    IMAGE_ANNOTATIONS,
    LOG,
    LOG_LEVELS,
    MAVLINK_RAW,
    SCHEMAS,
    Schema,
    mavlink_schema,
)

log = logging.getLogger(__name__)

GREEN: messages.Rgba = (0.1, 0.9, 0.2, 1.0)


@dataclass(frozen=True, slots=True)
class LogStats:
    """What a :class:`LogWriter` did so far (message counts).

    Attributes:
        queued: jobs accepted onto the queue (a MAVLink job is two messages).
        dropped: jobs refused because the queue was full or the writer closed.
        skipped: camera frames left out to keep ``frame_rate_hz``.
        written: messages handed to the MCAP writer (a file error also loses those of
            the chunk it was filling).
        lost: messages not written because of a file error or a failed encoding.
        errors: file errors and failed encodings met (the first of each outage is logged).
        files: every file opened, in order.
        last_error: the last error, one line naming the file, or None.
        over_quota: jobs of bulky topics not written because the log reached
            ``LogConfig.max_bytes``.
    """

    queued: int
    dropped: int
    skipped: int
    written: int
    lost: int
    errors: int
    files: tuple[Path, ...]
    last_error: str | None
    over_quota: int = 0


class _Job(NamedTuple):
    t_ns: int
    build: Callable[..., list[Record]]
    args: tuple[Any, ...]
    bulky: bool = False  # a frame, annotations or MAVLink: not written over the quota


class _Metadata(NamedTuple):
    name: str
    data: dict[str, str]


_STOP = object()


class LogWriter:
    """Logs to numbered MCAP files ``<output_dir>/<name>-NNNN.mcap`` from a writer thread.

    Every ``log_*`` method returns at once: True if the job was queued, False if it
    was dropped (queue full, writer closed) or skipped (frame rate). Bad arguments
    (wrong shape, unknown schema) are bugs and raise; file problems never do.

    Args:
        config: folder, frame rate, JPEG quality, flushing, rotation, queue size.
        name: file name prefix, e.g. ``"robot"`` or ``"ground"``.
        unix_offset_ns: Unix time minus the reading of the clock ``t_ns`` comes from, ns,
            >= 0 (module docstring); 0 for a clock that reads Unix time (and tests).

    Raises:
        ValueError: ``unix_offset_ns`` is negative or not an integer.
    """

    def __init__(self, config: LogConfig | None = None, name: str = "robot", *,
                 unix_offset_ns: int = 0) -> None:
        if not isinstance(unix_offset_ns, int) or unix_offset_ns < 0:
            raise ValueError(f"unix_offset_ns must be an integer >= 0, got {unix_offset_ns!r}")
        self.config = config or LogConfig()
        self.unix_offset_ns = unix_offset_ns
        self._files = McapFiles(self.config, name, unix_offset_ns)
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=self.config.queue_messages)
        self._lock = threading.Lock()
        self._queued = self._dropped = self._skipped = self._job_errors = self._job_lost = 0
        self._over_quota = 0
        self._quota_reached = False
        self._job_error: str | None = None
        self._frame_period_ns = round(NS_PER_S / self.config.frame_rate_hz)
        self._next_frame_ns: dict[str, int] = {}
        self._closed = False
        self._thread = threading.Thread(target=self._run, name=f"log-writer-{name}", daemon=True)
        self._thread.start()
        atexit.register(self.close)

    def log_image(self, t_ns: int, topic: str, image: npt.NDArray[np.uint8],
                  frame_id: str = topics.FRAME_CAMERA, *, lossless: bool = False) -> bool:
        """Log a grey frame as a JPEG ``foxglove.CompressedImage``, at most ``frame_rate_hz``;
        or, ``lossless``, as a PNG one whatever the rate (every frame replay needs).

        Args:
            t_ns: capture time, ns.
            topic: e.g. :data:`topics.CAMERA_IMAGE`.
            image: (H, W) uint8 grey; copied, so the caller may reuse its buffer.
            frame_id: the camera's frame.
            lossless: PNG (decodes to ``image`` exactly), not rate-limited.

        Returns:
            Whether the frame was queued; log its annotations only if so.
        """
        check_shape("image", np.shape(image), (None, None))
        if np.asarray(image).dtype != np.uint8:
            raise ValueError(f"image: expected uint8 grey, got {np.asarray(image).dtype}")
        stamp_ns = t_ns + self.unix_offset_ns
        if lossless:
            return self._put(_Job(t_ns, _image_records, (stamp_ns, topic, frame_id,
                                                          np.array(image), "png", []), bulky=True))
        if not self._frame_due(t_ns, topic):
            return False
        return self._put(_Job(t_ns, _image_records, (
            stamp_ns, topic, frame_id, np.array(image), "jpeg",
            [cv2.IMWRITE_JPEG_QUALITY, self.config.jpeg_quality]), bulky=True))

    def log_points(self, t_ns: int, topic: str, pixels_xy: npt.ArrayLike, *,
                   color: messages.Rgba = GREEN, thickness_px: float = 4.0,
                   label: str | None = None) -> bool:
        """Log points on an image as ``foxglove.ImageAnnotations``.

        Args:
            t_ns: the image's ``t_ns`` exactly (the Image panel pairs them by timestamp).
            topic: e.g. :data:`topics.CAMERA_ANNOTATIONS`.
            pixels_xy: (N, 2) pixel coordinates, origin at the top-left corner of the
                top-left pixel.
            color: RGBA in [0, 1].
            thickness_px: point size, px.
            label: optional text, e.g. ``"key 42: 117 matches"``.
        """
        pixels = np.array(pixels_xy, np.float64)
        check_shape("pixels_xy", pixels.shape, (None, 2))
        return self._put(_Job(t_ns, _one, (topic, IMAGE_ANNOTATIONS, messages.image_points,
                                           t_ns + self.unix_offset_ns, pixels, color,
                                           thickness_px, label), bulky=True))

    def log_json(self, t_ns: int, topic: str, schema_name: str,
                 message: Mapping[str, Any]) -> bool:
        """Log a JSON message under one of :data:`~shared.logs.schemas.SCHEMAS`.

        Args:
            t_ns: log time, ns.
            topic: e.g. :data:`topics.SERVO_STATE`.
            schema_name: e.g. ``"vmnav.ServoState"``.
            message: the fields (copied, one level deep).

        Raises:
            ValueError: ``schema_name`` is not a known schema.
        """
        if schema_name not in SCHEMAS:
            raise ValueError(f"unknown log schema {schema_name!r} (known: {', '.join(SCHEMAS)})")
        return self._put(_Job(t_ns, _one, (topic, SCHEMAS[schema_name], dict, dict(message))))

    def log_transform(self, t_ns: int, transforms: Sequence[messages.FrameTransform],
                      topic: str = topics.TF) -> bool:
        """Log ``foxglove.FrameTransforms``, every transform stamped ``t_ns``."""
        return self._put(_Job(t_ns, _one, (topic, FRAME_TRANSFORMS, messages.frame_transforms,
                                           t_ns + self.unix_offset_ns, tuple(transforms))))

    def log_text(self, t_ns: int, level: str, message: str, name: str,
                 topic: str = topics.LOG) -> bool:
        """Log a ``foxglove.Log`` line; ``level`` is DEBUG, INFO, WARNING, ERROR or FATAL.

        Raises:
            ValueError: an unknown ``level``.
        """
        if level not in LOG_LEVELS:
            raise ValueError(f"unknown log level {level!r} (known: {', '.join(LOG_LEVELS)})")
        return self._put(_Job(t_ns, _one, (topic, LOG, messages.log_entry,
                                           t_ns + self.unix_offset_ns, level, message, name)))

    def log_mavlink(self, t_ns: int, msg: Any, direction: str) -> bool:
        """Log a pymavlink message on ``/mavlink/<direction>/<NAME>`` and its packet on
        ``/mavlink/raw`` (the raw frame only once the message was packed or parsed).

        Args:
            t_ns: time it was received or sent, ns.
            msg: a decoded or packed pymavlink message; not changed afterwards.
            direction: ``"in"`` (received) or ``"out"`` (sent).
        """
        if direction not in topics.MAVLINK_DIRECTIONS:
            raise ValueError(f"direction must be 'in' or 'out', got {direction!r}")
        frame = msg.get_msgbuf()
        return self._put(_Job(t_ns, _mavlink_records,
                              (direction, msg, bytes(frame) if frame else b""), bulky=True))

    def log_mavlink_packet(self, t_ns: int, packet: bytes, direction: str) -> bool:
        """Log one MAVLink packet given as its bytes, as :meth:`log_mavlink` does; the
        writer thread parses it (a packet that does not parse is counted as lost).

        Args:
            t_ns: time it was received or sent, ns.
            packet: one whole MAVLink 1 or 2 packet, header to checksum (signature included).
            direction: ``"in"`` (received) or ``"out"`` (sent).
        """
        if direction not in topics.MAVLINK_DIRECTIONS:
            raise ValueError(f"direction must be 'in' or 'out', got {direction!r}")
        return self._put(_Job(t_ns, _packet_records, (direction, bytes(packet)), bulky=True))

    def add_metadata(self, name: str, data: Mapping[str, str]) -> bool:
        """Store key-value metadata (e.g. ``"run"``: route, mode, git sha) in every file."""
        return self._put(_Metadata(name, {str(k): str(v) for k, v in data.items()}))

    def stats(self) -> LogStats:
        """A snapshot of the counters."""
        files = self._files
        with self._lock:
            return LogStats(queued=self._queued, dropped=self._dropped, skipped=self._skipped,
                            written=files.written, lost=files.lost + self._job_lost,
                            errors=files.errors + self._job_errors,
                            files=tuple(files.paths),
                            last_error=files.last_error or self._job_error,
                            over_quota=self._over_quota)

    def close(self, timeout_s: float = 10.0) -> LogStats:
        """Write what is queued, finish the file (summary, index) and stop the thread.

        Safe to call twice; runs at interpreter exit if not called.

        Args:
            timeout_s: wait at most this long for the thread, s.
        """
        with self._lock:
            closing, self._closed = not self._closed, True
        if closing:
            atexit.unregister(self.close)
            try:
                self._queue.put(_STOP, timeout=timeout_s)
            except queue.Full:
                log.error("log writer: queue still full after %.1f s; file left unfinished",
                          timeout_s)
            self._thread.join(timeout_s)
        return self.stats()

    def __enter__(self) -> LogWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _frame_due(self, t_ns: int, topic: str) -> bool:
        # Frames are due on a grid one period apart and accepted up to a quarter period
        # early, so camera jitter does not halve the rate; the grid only moves to follow
        # a frame more than that late. Accepts stay at least a period apart on average.
        period, slack = self._frame_period_ns, self._frame_period_ns // 4
        with self._lock:
            due = self._next_frame_ns.get(topic, t_ns)
            if t_ns < due - slack:
                self._skipped += 1
                return False
            self._next_frame_ns[topic] = max(due + period, t_ns + period - slack)
            return True

    def _put(self, job: _Job | _Metadata) -> bool:
        if isinstance(job, _Job) and job.t_ns < 0:
            raise ValueError(f"t_ns must be >= 0, got {job.t_ns}")
        with self._lock:
            if isinstance(job, _Job) and job.bulky and self._quota_reached:
                self._over_quota += 1
                return False
            if not self._closed:
                try:
                    self._queue.put_nowait(job)
                    self._queued += 1
                    return True
                except queue.Full:
                    pass
            self._dropped += 1
            return False

    def _run(self) -> None:
        clock = WallClock()  # real time: the flush period bounds what a kill loses
        files = self._files
        files.open(clock.now_ns())
        flush_due_ns: int | None = None
        while True:
            timeout_s = (None if flush_due_ns is None
                         else max(0, flush_due_ns - clock.now_ns()) / NS_PER_S)
            try:
                job = self._queue.get(timeout=timeout_s)
            except queue.Empty:
                job = None
            if job is _STOP:
                break
            if isinstance(job, _Metadata):
                files.add_metadata(job.name, job.data, clock.now_ns())
            elif job is not None:
                self._write(job, clock.now_ns())
            if job is not None and flush_due_ns is None:
                flush_due_ns = clock.now_ns() + self.config.flush_period_ns
            if flush_due_ns is not None and clock.now_ns() >= flush_due_ns:
                files.flush(clock.now_ns())
                flush_due_ns = None
        files.close(clock.now_ns())

    def _write(self, job: _Job, now_ns: int) -> None:
        if job.bulky and self._over(job.t_ns, now_ns):
            return
        try:
            self._files.write(job.t_ns, job.build(*job.args), now_ns)
        except Exception as e:  # a bad message (or a bug) must not stop the writer thread
            with self._lock:
                self._job_errors += 1
                self._job_lost += 1
                first = self._job_error is None
                self._job_error = f"{job.build.__name__}: {e}"
            if first:
                log.exception("cannot log a message (%s); counted, not logged",
                              job.build.__name__)


    def _over(self, t_ns: int, now_ns: int) -> bool:
        """Whether the quota is reached (the writer thread); the first time, count and say so."""
        with self._lock:
            if self._quota_reached:
                self._over_quota += 1
                return True
        limit = self.config.max_bytes
        if self._files.size_bytes < limit:
            return False
        with self._lock:
            self._quota_reached = True
            self._over_quota += 1
        text = (f"log quota of {limit} bytes reached: camera frames and MAVLink are no longer "
                f"logged (LogConfig.max_bytes)")
        log.warning("%s in %s", text, self.config.output_dir)
        entry = messages.log_entry(t_ns + self.unix_offset_ns, "WARNING", text, __name__)
        self._files.write(t_ns, [(topics.LOG, LOG, entry)], now_ns)
        return True


def _one(topic: str, schema: Schema, build: Callable[..., Mapping[str, Any]],
         *args: Any) -> list[Record]:
    return [(topic, schema, build(*args))]


def _image_records(stamp_ns: int, topic: str, frame_id: str, image: npt.NDArray[np.uint8],
                   fmt: str, params: list[int]) -> list[Record]:
    ok, data = cv2.imencode(f".{fmt}", image, params)
    if not ok:
        raise ValueError(f"cv2.imencode failed on a {image.shape} image")
    return [(topic, COMPRESSED_IMAGE, messages.compressed_image(stamp_ns, frame_id,
                                                                data.tobytes(), fmt))]


def _packet_records(direction: str, packet: bytes) -> list[Record]:
    # Imported here: the dialect takes a third of a second to import, and only logs
    # of MAVLink packets need it.
    from shared.mavlink.dialect import make_codec

    parsed = make_codec(0, 0).parse(packet)  # a fresh parser: no state across packets
    if len(parsed) != 1:
        raise ValueError(f"not one MAVLink packet: {len(packet)} bytes gave {len(parsed)} "
                         f"messages")
    return _mavlink_records(direction, parsed[0], packet)


def _mavlink_records(direction: str, msg: Any, frame: bytes) -> list[Record]:
    records: list[Record] = [(topics.mavlink_topic(direction, msg.get_type()),
                              mavlink_schema(type(msg)), messages.mavlink_fields(msg))]
    if frame:
        records.append((topics.MAVLINK_RAW, MAVLINK_RAW,
                        messages.mavlink_raw(direction, msg, frame)))
    return records
