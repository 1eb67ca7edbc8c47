"""A camera's frames as MJPEG over HTTP: the simulator's network camera and the robot's
live view (``vmnav robot --video``).

A real network camera is read through ``cv2.VideoCapture(URL)``; a browser shows the
stream in an ``<img>``. The simulator serves its rendered frames this way
(:mod:`sim.camera_server`), and the robot serves what its camera sees, smaller and
slower, with the points its vision matched (:mod:`robot.video`).

Rules:

1. **Frames in.** :meth:`MjpegServer.publish` takes each new frame (and, optionally, the
   points to draw on it) from the caller's loop and returns at once: it keeps a
   reference to the newest frame under a lock held for a few assignments, never while
   encoding. Only the newest frame is kept.
2. **Encoding in the clients' threads.** A frame is scaled to ``width_px`` (when given),
   drawn on (for the ``?matches=1`` view) and JPEG-encoded once per view, on demand, by
   the first client thread that sends it; the others wait for that encoding, not the
   publisher.
3. **Out.** ``GET /stream.mjpg``: ``multipart/x-mixed-replace``, one JPEG part per
   published frame; a client that falls behind skips to the newest frame (nothing
   queues). ``GET /snapshot.jpg``: the newest frame as one JPEG (503 before the first).
   ``?matches=1`` on either draws the points given with the frame (green: inliers of
   the vision's estimate, orange: the other matches). ``GET /matches.json``: those
   points of the newest frame as JSON, with the points of the key image they were
   matched with when given (:func:`matches_json`; 503 before the first frame), so a
   page can draw them on the key image beside the stream. Anything else: 404. Grey frames
   give grey JPEGs (OpenCV decodes them to three equal channels, which
   ``cv2.COLOR_BGR2GRAY`` turns back exactly).
4. **Threads.** One thread accepts, one thread per client writes. A client that goes
   away ends its own thread; one that stops reading for
   :attr:`~shared.guarded_http.HttpLimits.handler_timeout_s` too. The publisher never
   waits for a client. :meth:`MjpegServer.close` shuts every client's socket, stops
   accepting and joins every thread; idempotent.
5. **Hostile clients** (:mod:`shared.guarded_http`): connections that send nothing hold
   no thread and are closed after a while; at most ``max_clients`` requests are served
   at once (a stream is one until it ends), others get 503 at once; a request from a web
   page of another origin, or with a DNS-rebound ``Host``, gets 403.
6. **Faults** (the simulator's fault scenarios and the clients' tests).
   :meth:`MjpegServer.stall` withholds the frames of the next stretch of frame time
   (clients stay connected and receive nothing); :meth:`MjpegServer.corrupt` sends the
   next frames as bytes that do not decode.
"""

from __future__ import annotations

import contextlib
import json
import logging
import socket
import threading
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import parse_qs, urlsplit

import cv2
import numpy as np
import numpy.typing as npt

from shared.errors import ShapeError, TransportError
from shared.guarded_http import GuardedHandler, GuardedHTTPServer, HttpLimits

log = logging.getLogger(__name__)

STREAM_PATH = "/stream.mjpg"
SNAPSHOT_PATH = "/snapshot.jpg"
#: The newest frame's matches as JSON (rule 3), beside the stream on the same server.
MATCHES_PATH = "/matches.json"
#: The query that asks for the matched points drawn (rule 3).
MATCHES_QUERY = "matches=1"
BOUNDARY = "vmnavframe"
DEFAULT_JPEG_QUALITY = 80
"""cv2.IMWRITE_JPEG_QUALITY unless told."""
MAX_CLIENTS = 16
"""Requests served at once unless told (rule 5): streams, snapshots."""
_POLL_S = 0.05
"""The accept loop checks for :meth:`MjpegServer.close` this often, s."""
_CORRUPT_XOR = 0x5A
"""A corrupt frame is its JPEG with every byte XORed with this: no start-of-image marker."""
_INLIER_BGR = (60, 200, 60)
_OTHER_BGR = (0, 140, 255)
_POINT_RADIUS_PX = 3


@dataclass(frozen=True, slots=True)
class MjpegStats:
    """Counts of a :class:`MjpegServer`.

    Attributes:
        published: frames handed to :meth:`MjpegServer.publish`.
        withheld: of those, frames held back by a stall.
        corrupted: of those, frames sent as bytes that do not decode.
        clients: stream clients connected so far.
        streaming: stream clients connected now.
    """

    published: int
    withheld: int
    corrupted: int
    clients: int
    streaming: int


def scaled_size(size_wh: tuple[int, int], width_px: int | None) -> tuple[int, int]:
    """The (width, height) of a frame of ``size_wh`` as served: scaled to ``width_px``
    wide, the aspect kept (``size_wh`` itself when ``width_px`` is None or not smaller)."""
    width, height = size_wh
    if width_px is None or width_px >= width:
        return width, height
    return width_px, max(1, round(height * width_px / width))


@dataclass(eq=False)
class _Frame:
    """A frame published, and its JPEG per view (made once, under ``lock``: rule 2)."""

    seq: int
    t_ns: int
    image: npt.NDArray[np.uint8]
    points_xy: npt.NDArray[np.float64] | None
    inliers: npt.NDArray[np.bool_] | None
    key_xy: npt.NDArray[np.float64] | None
    key_id: int | None
    corrupt: bool
    jpegs: dict[bool, bytes] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)


class _FrameBoard:
    """The newest frame and the clients waiting for it (rules 1, 2, 6)."""

    def __init__(self, jpeg_quality: int, width_px: int | None) -> None:
        self._quality = jpeg_quality
        self._width_px = width_px
        self._changed = threading.Condition()
        self._frame: _Frame | None = None
        self._seq = 0  # of the newest frame delivered; 0: none yet
        self._newest_t_ns = 0  # frame time of the newest frame published, delivered or not
        self._stall_until_ns: int | None = None
        self._corrupt_left = 0
        self._closed = False
        self._published = self._withheld = self._corrupted = 0
        self._clients = self._streaming = 0

    def publish(self, t_ns: int, image: npt.NDArray[np.uint8],
                points_xy: npt.NDArray[np.float64] | None,
                inliers: npt.NDArray[np.bool_] | None,
                key_xy: npt.NDArray[np.float64] | None, key_id: int | None) -> None:
        with self._changed:
            self._published += 1
            self._newest_t_ns = t_ns
            if self._stall_until_ns is not None and t_ns < self._stall_until_ns:
                self._withheld += 1
                return
            self._stall_until_ns = None
            corrupt = self._corrupt_left > 0
            if corrupt:
                self._corrupt_left -= 1
                self._corrupted += 1
            self._seq += 1
            self._frame = _Frame(self._seq, t_ns, image, points_xy, inliers, key_xy, key_id,
                                 corrupt)
            self._changed.notify_all()

    def stall(self, duration_ns: int) -> None:
        with self._changed:
            self._stall_until_ns = self._newest_t_ns + duration_ns

    def corrupt(self, count: int) -> None:
        with self._changed:
            self._corrupt_left = count

    def wait_next(self, after_seq: int, matches: bool) -> tuple[int, bytes] | None:
        """The JPEG of the newest frame after ``after_seq``, waiting for it; None once closed."""
        with self._changed:
            self._changed.wait_for(lambda: self._closed or self._seq > after_seq)
            if self._closed:
                return None
            frame = self._frame
        assert frame is not None
        return frame.seq, self._encoded(frame, matches)

    def newest(self, matches: bool) -> bytes | None:
        """The JPEG of the newest frame delivered, or None before the first."""
        with self._changed:
            frame = self._frame
        return None if frame is None else self._encoded(frame, matches)

    def newest_matches(self) -> bytes | None:
        """The newest frame's matches as JSON (:func:`matches_json`), or None before the
        first frame."""
        with self._changed:
            frame = self._frame
        if frame is None:
            return None
        height, width = frame.image.shape[:2]
        return json.dumps(matches_json(frame.seq, frame.t_ns, (width, height), frame.points_xy,
                                       frame.inliers, frame.key_xy, frame.key_id),
                          separators=(",", ":")).encode()

    def _encoded(self, frame: _Frame, matches: bool) -> bytes:
        """The frame's JPEG for the view, made by the first client that asks (rule 2)."""
        matches = matches and frame.points_xy is not None and len(frame.points_xy) > 0
        with frame.lock:
            jpeg = frame.jpegs.get(matches)
            if jpeg is None:
                jpeg = frame.jpegs[matches] = self._encode(frame, matches)
            return jpeg

    def _encode(self, frame: _Frame, matches: bool) -> bytes:
        image = frame.image
        height, width = image.shape[:2]
        out_w, out_h = scaled_size((width, height), self._width_px)
        if (out_w, out_h) != (width, height):
            image = cv2.resize(image, (out_w, out_h), interpolation=cv2.INTER_AREA)
        if matches:
            assert frame.points_xy is not None
            image = _draw_points(image, frame.points_xy * (out_w / width), frame.inliers)
        ok, buffer = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self._quality])
        if not ok:  # publish() lets only uint8 grey or BGR images in; cv2 takes any
            raise RuntimeError(f"cv2.imencode failed on an image {image.shape}")
        if frame.corrupt:
            buffer = buffer ^ np.uint8(_CORRUPT_XOR)
        return bytes(buffer.tobytes())

    def count_client(self, delta: int) -> None:
        """A stream client came (+1) or went (-1)."""
        with self._changed:
            self._clients += max(delta, 0)
            self._streaming += delta

    def stats(self) -> MjpegStats:
        with self._changed:
            return MjpegStats(self._published, self._withheld, self._corrupted,
                              self._clients, self._streaming)

    def close(self) -> None:
        with self._changed:
            self._closed = True
            self._changed.notify_all()


def matches_json(seq: int, t_ns: int, size_wh: tuple[int, int],
                 points_xy: npt.NDArray[np.float64] | None,
                 inliers: npt.NDArray[np.bool_] | None,
                 key_xy: npt.NDArray[np.float64] | None, key_id: int | None) -> dict[str, Any]:
    """What ``GET /matches.json`` answers for a frame (rule 3).

    Returns:
        ``{"seq", "t_ns", "size": [W, H] of the frame as published (not scaled),
        "key": the key image's id or None, "frame_xy": [[x, y], ...] px of the frame,
        "key_xy": [[x, y], ...] px of the key image (the same matches, in order) or None,
        "inliers": [bool, ...] or None}``, pixels rounded to 0.1 px. Key points whose
        count differs from the frame's are left out (None), and so are inliers.
    """
    frame = np.zeros((0, 2)) if points_xy is None else points_xy
    key = None if key_xy is None or len(key_xy) != len(frame) else key_xy
    return {"seq": seq, "t_ns": t_ns, "size": list(size_wh),
            "key": key_id if key is not None else None,
            "frame_xy": np.round(frame, 1).tolist(),
            "key_xy": None if key is None else np.round(key, 1).tolist(),
            "inliers": None if inliers is None or len(inliers) != len(frame)
            else [bool(v) for v in inliers]}


def _draw_points(image: npt.NDArray[np.uint8], points_xy: npt.NDArray[np.float64],
                 inliers: npt.NDArray[np.bool_] | None) -> npt.NDArray[np.uint8]:
    """A BGR copy of ``image`` with a small circle on each point (rule 3)."""
    out = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image.copy()
    centres = np.rint(points_xy).astype(np.int32)
    for k, (x, y) in enumerate(centres):
        inlier = inliers is not None and k < len(inliers) and bool(inliers[k])
        cv2.circle(out, (int(x), int(y)), _POINT_RADIUS_PX,
                   _INLIER_BGR if inlier else _OTHER_BGR, 1, cv2.LINE_AA)
    return out


class _HttpServer(GuardedHTTPServer):
    """Client threads are joined at close; their sockets are tracked to be shut (rule 4)."""

    def __init__(self, address: tuple[str, int], board: _FrameBoard, max_clients: int) -> None:
        self.board = board
        self._connections: set[socket.socket] = set()
        self._lock = threading.Lock()
        self._dropping = False
        super().__init__(address, _Handler, HttpLimits(max_handlers=max_clients))

    def track(self, conn: socket.socket) -> None:
        """A client's socket, shut at once if :meth:`drop_all` has begun."""
        with self._lock:
            self._connections.add(conn)
            if self._dropping:
                _shut(conn)

    def untrack(self, conn: socket.socket) -> None:
        with self._lock:
            self._connections.discard(conn)

    def drop_all(self) -> None:
        """Shut every client's socket, now and from now on (unblocks a stuck write)."""
        with self._lock:
            self._dropping = True
            for conn in self._connections:
                _shut(conn)


def _shut(conn: socket.socket) -> None:
    with contextlib.suppress(OSError):  # already gone
        conn.shutdown(socket.SHUT_RDWR)


class _Handler(GuardedHandler):
    server: _HttpServer
    protocol_version = "HTTP/1.0"  # one request per connection; a stream ends with it

    def setup(self) -> None:
        super().setup()
        self.server.track(self.connection)

    def finish(self) -> None:
        self.server.untrack(self.connection)
        with contextlib.suppress(OSError):  # the client is gone; nothing is left to flush
            super().finish()

    def do_GET(self) -> None:  # noqa: N802 - http.server names the method
        url = urlsplit(self.path)
        matches = parse_qs(url.query).get("matches") == ["1"]
        try:
            if (refused := self.refusal()) is not None:
                self.send_error(refused.status, refused.reason)
            elif url.path == STREAM_PATH:
                self._stream(matches)
            elif url.path == SNAPSHOT_PATH:
                self._snapshot(matches)
            elif url.path == MATCHES_PATH:
                self._matches()
            else:
                self.send_error(404, f"try {STREAM_PATH}, {SNAPSHOT_PATH} or {MATCHES_PATH}")
        except OSError as e:  # the client went away (reset, broken pipe, shut at close)
            log.debug("camera client %s:%s gone: %s", *self.client_address, e)

    def _stream(self, matches: bool) -> None:
        board = self.server.board
        board.count_client(+1)
        try:
            self.send_response(200)
            self.send_header("Content-Type", f"multipart/x-mixed-replace; boundary={BOUNDARY}")
            self.send_header("Cache-Control", "no-cache, no-store")
            self.send_header("Pragma", "no-cache")
            self.end_headers()
            seq = 0
            while (part := board.wait_next(seq, matches)) is not None:
                seq, jpeg = part
                head = (f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\n"
                        f"Content-Length: {len(jpeg)}\r\n\r\n").encode("ascii")
                self.wfile.write(head + jpeg + b"\r\n")
        finally:
            board.count_client(-1)

    def _snapshot(self, matches: bool) -> None:
        jpeg = self.server.board.newest(matches)
        if jpeg is None:
            self.send_error(503, "no frame yet")
            return
        self.send_response(200)
        self.send_header("Content-Type", "image/jpeg")
        self.send_header("Content-Length", str(len(jpeg)))
        self.send_header("Cache-Control", "no-cache, no-store")
        self.end_headers()
        self.wfile.write(jpeg)

    def _matches(self) -> None:
        body = self.server.board.newest_matches()
        if body is None:
            self.send_error(503, "no frame yet")
            return
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-cache, no-store")
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: object) -> None:
        log.debug("camera client %s: " + format, self.address_string(), *args)


class MjpegServer:
    """MJPEG over HTTP of the frames given to :meth:`publish` (see the module rules).

    Serves from construction until :meth:`close`.

    Args:
        host: address to bind (``127.0.0.1``: this machine only; ``0.0.0.0``: every
            interface).
        port: TCP port; 0 picks a free one (see :attr:`port`).
        jpeg_quality: cv2.IMWRITE_JPEG_QUALITY, 1-100.
        width_px: frames wider than this are scaled down to it (aspect kept); None:
            served at their own size.
        max_clients: requests served at once (rule 5).

    Raises:
        ValueError: ``jpeg_quality`` outside 1-100, ``width_px`` or ``max_clients`` < 1.
        TransportError: the address cannot be bound (in use, not local, bad name).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 jpeg_quality: int = DEFAULT_JPEG_QUALITY, *, width_px: int | None = None,
                 max_clients: int = MAX_CLIENTS) -> None:
        if not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be in 1..100, got {jpeg_quality}")
        if width_px is not None and width_px < 1:
            raise ValueError(f"width_px must be >= 1, got {width_px}")
        if max_clients < 1:
            raise ValueError(f"max_clients must be >= 1, got {max_clients}")
        self.host = host
        self.width_px = width_px
        self._board = _FrameBoard(jpeg_quality, width_px)
        try:
            self._http = _HttpServer((host, port), self._board, max_clients)
        except OSError as e:
            raise TransportError(f"http:{host}:{port}",
                                 f"cannot listen: {e.strerror or e}") from None
        self._thread = threading.Thread(target=self._http.serve_forever, args=(_POLL_S,),
                                        name="mjpeg-server")
        self._thread.start()
        self._closed = False

    def __enter__(self) -> MjpegServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def port(self) -> int:
        """The port it listens on (the real one when created with port 0)."""
        return int(self._http.server_address[1])

    @property
    def stream_url(self) -> str:
        """The MJPEG stream, for ``cv2.VideoCapture``, ffplay or a browser."""
        return f"http://{_url_host(self.host)}:{self.port}{STREAM_PATH}"

    @property
    def matches_url(self) -> str:
        """The newest frame's matches as JSON (rule 3)."""
        return f"http://{_url_host(self.host)}:{self.port}{MATCHES_PATH}"

    @property
    def snapshot_url(self) -> str:
        """The newest frame as one JPEG."""
        return f"http://{_url_host(self.host)}:{self.port}{SNAPSHOT_PATH}"

    def publish(self, t_ns: int, image: npt.NDArray[np.uint8],
                points_xy: npt.NDArray[np.float64] | None = None,
                inliers: npt.NDArray[np.bool_] | None = None, *,
                key_xy: npt.NDArray[np.float64] | None = None,
                key_id: int | None = None) -> None:
        """A new frame for every client (rule 1); never waits for a client.

        Args:
            t_ns: exposure time, ns (frame time: what :meth:`stall` measures).
            image: (H, W) uint8 grey or (H, W, 3) uint8 BGR; kept, not copied, so the
                caller must not modify it afterwards.
            points_xy: (N, 2) float64 pixels of ``image`` (x right, y down, OpenCV's
                centres at integers) to draw in the ``?matches=1`` view; None: none.
            inliers: (N,) bool, which of ``points_xy`` to draw as inliers; None: none.
            key_xy: (N, 2) float64 pixels of the key image ``key_id`` that ``points_xy``
                were matched with, in order, for ``/matches.json``; None: not known.
            key_id: the key image's id.

        Raises:
            ShapeError: ``image`` is neither, or ``points_xy`` or ``key_xy`` is not (N, 2).
        """
        if image.dtype != np.uint8 or not (image.ndim == 2 or image.shape[2:] == (3,)):
            raise ShapeError(f"image: expected (H, W) or (H, W, 3) uint8, got {image.shape} "
                             f"{image.dtype}")
        if points_xy is not None and (points_xy.ndim != 2 or points_xy.shape[1] != 2):
            raise ShapeError(f"points_xy: expected (N, 2), got {points_xy.shape}")
        if key_xy is not None and (points_xy is None or key_xy.shape != points_xy.shape):
            raise ShapeError(f"key_xy: expected the shape of points_xy, got {key_xy.shape}")
        self._board.publish(t_ns, image, points_xy, inliers, key_xy, key_id)

    def stall(self, duration_ns: int) -> None:
        """Withhold the frames from the newest one published until ``duration_ns`` later
        in frame time (replaces a stall in progress); clients stay connected."""
        self._board.stall(duration_ns)

    def corrupt(self, count: int) -> None:
        """Send the next ``count`` frames delivered as bytes that are not a JPEG."""
        self._board.corrupt(count)

    def stats(self) -> MjpegStats:
        """The counts so far."""
        return self._board.stats()

    def close(self) -> None:
        """Drop every client, stop serving and join the threads (rule 4); idempotent."""
        if self._closed:
            return
        self._closed = True
        self._http.shutdown()
        self._board.close()
        self._http.drop_all()
        self._http.server_close()
        self._thread.join()


def matches_url(stream_url: str) -> str:
    """The ``/matches.json`` beside a stream of this server (``http://H:P/stream.mjpg``
    -> ``http://H:P/matches.json``): where a viewer that found the stream (the camera
    protocol advertises it alone) finds the matches of its frames."""
    url = urlsplit(stream_url)
    return url._replace(path=MATCHES_PATH, query="", fragment="").geturl()


def _url_host(host: str) -> str:
    """``host`` as a URL has it (an IPv6 address in brackets)."""
    return f"[{host}]" if ":" in host else host
