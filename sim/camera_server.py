"""The simulator's network camera: frames as MJPEG over HTTP (issue 8).

The robot reads it like a real network camera, through ``cv2.VideoCapture(URL)``.

Rules:

1. **Frames in.** :meth:`CameraServer.publish` takes each new frame, from the
   simulation loop (:class:`CameraFeed`, a step hook). Only the newest frame is kept;
   it is JPEG-encoded once, on demand, by the first client thread that sends it.
2. **Out.** ``GET /stream.mjpg``: ``multipart/x-mixed-replace``, one JPEG part per
   published frame; a client that falls behind skips to the newest frame (nothing
   queues). ``GET /snapshot.jpg``: the newest frame as one JPEG (503 before the
   first). Anything else: 404. Frames are grey JPEGs (OpenCV decodes them to
   three equal channels, which ``cv2.COLOR_BGR2GRAY`` turns back exactly).
3. **Threads.** One thread accepts, one thread per client writes. A client that
   goes away ends its own thread; one that stops reading for
   :attr:`~sim.guarded_http.HttpLimits.handler_timeout_s` too. The simulation loop
   never waits for a client. :meth:`CameraServer.close` shuts every client's socket,
   stops accepting and joins every thread; idempotent.
4. **Hostile clients** (:mod:`sim.guarded_http`): connections that send nothing hold
   no thread and are closed after a while; at most :data:`MAX_CLIENTS` requests are
   served at once (a stream is one until it ends), others get 503; a request from a
   web page of another origin, or with a DNS-rebound ``Host``, gets 403.
5. **Faults** (tests, issue 8's fault scenarios). :meth:`CameraServer.stall`
   withholds the frames of the next stretch of frame time (clients stay connected
   and receive nothing); :meth:`CameraServer.corrupt` sends the next frames as
   bytes that do not decode.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
from dataclasses import dataclass
from urllib.parse import urlsplit

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.errors import ShapeError, TransportError
from sim.config import SensorConfig
from sim.guarded_http import GuardedHandler, GuardedHTTPServer, HttpLimits
from sim.renderer import FisheyeRenderer, RenderedFrame
from sim.simulation import Simulation

log = logging.getLogger(__name__)

STREAM_PATH = "/stream.mjpg"
SNAPSHOT_PATH = "/snapshot.jpg"
BOUNDARY = "vmnavframe"
DEFAULT_JPEG_QUALITY = SensorConfig().jpeg_quality
"""cv2.IMWRITE_JPEG_QUALITY of the served frames unless told (``[sim.sensor]
jpeg_quality``: the simulated camera's MJPEG)."""
_POLL_S = 0.05
"""The accept loop checks for :meth:`CameraServer.close` this often, s."""
_CORRUPT_XOR = 0x5A
MAX_CLIENTS = 16
"""Requests served at once (rule 4): streams, snapshots."""
"""A corrupt frame is its JPEG with every byte XORed with this: no start-of-image marker."""


@dataclass(frozen=True, slots=True)
class CameraServerStats:
    """Counts of a :class:`CameraServer`.

    Attributes:
        published: frames handed to :meth:`CameraServer.publish`.
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


class _FrameBoard:
    """The newest frame, its JPEG (made once, on demand) and the clients waiting for it."""

    def __init__(self, jpeg_quality: int) -> None:
        self._quality = jpeg_quality
        self._changed = threading.Condition()
        self._seq = 0  # of the newest frame delivered; 0: none yet
        self._image: npt.NDArray[np.uint8] | None = None
        self._jpeg: bytes | None = None
        self._corrupt_frame = False
        self._newest_t_ns = 0  # frame time of the newest frame published, delivered or not
        self._stall_until_ns: int | None = None
        self._corrupt_left = 0
        self._closed = False
        self._published = self._withheld = self._corrupted = 0
        self._clients = self._streaming = 0

    def publish(self, t_ns: int, image: npt.NDArray[np.uint8]) -> None:
        with self._changed:
            self._published += 1
            self._newest_t_ns = t_ns
            if self._stall_until_ns is not None and t_ns < self._stall_until_ns:
                self._withheld += 1
                return
            self._stall_until_ns = None
            self._corrupt_frame = self._corrupt_left > 0
            if self._corrupt_frame:
                self._corrupt_left -= 1
                self._corrupted += 1
            self._seq += 1
            self._image, self._jpeg = image, None
            self._changed.notify_all()

    def stall(self, duration_ns: int) -> None:
        with self._changed:
            self._stall_until_ns = self._newest_t_ns + duration_ns

    def corrupt(self, count: int) -> None:
        with self._changed:
            self._corrupt_left = count

    def wait_next(self, after_seq: int) -> tuple[int, bytes] | None:
        """The JPEG of the newest frame after ``after_seq``, waiting for it; None once closed."""
        with self._changed:
            self._changed.wait_for(lambda: self._closed or self._seq > after_seq)
            if self._closed:
                return None
            return self._seq, self._encoded()

    def newest(self) -> bytes | None:
        """The JPEG of the newest frame delivered, or None before the first."""
        with self._changed:
            return None if self._seq == 0 else self._encoded()

    def _encoded(self) -> bytes:
        if self._jpeg is None:
            assert self._image is not None
            ok, buffer = cv2.imencode(".jpg", self._image,
                                      [cv2.IMWRITE_JPEG_QUALITY, self._quality])
            if not ok:  # publish() lets only uint8 grey or BGR images in; cv2 takes any
                raise RuntimeError(f"cv2.imencode failed on an image {self._image.shape}")
            if self._corrupt_frame:
                buffer = buffer ^ np.uint8(_CORRUPT_XOR)
            self._jpeg = buffer.tobytes()
        return self._jpeg

    def count_client(self, delta: int) -> None:
        """A stream client came (+1) or went (-1)."""
        with self._changed:
            self._clients += max(delta, 0)
            self._streaming += delta

    def stats(self) -> CameraServerStats:
        with self._changed:
            return CameraServerStats(self._published, self._withheld, self._corrupted,
                                     self._clients, self._streaming)

    def close(self) -> None:
        with self._changed:
            self._closed = True
            self._changed.notify_all()


class _HttpServer(GuardedHTTPServer):
    """Client threads are joined at close; their sockets are tracked to be shut (rule 3)."""

    def __init__(self, address: tuple[str, int], board: _FrameBoard) -> None:
        self.board = board
        self._connections: set[socket.socket] = set()
        self._lock = threading.Lock()
        self._dropping = False
        super().__init__(address, _Handler, HttpLimits(max_handlers=MAX_CLIENTS))

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
        path = urlsplit(self.path).path
        try:
            if (refused := self.refusal()) is not None:
                self.send_error(refused.status, refused.reason)
            elif path == STREAM_PATH:
                self._stream()
            elif path == SNAPSHOT_PATH:
                self._snapshot()
            else:
                self.send_error(404, f"try {STREAM_PATH} or {SNAPSHOT_PATH}")
        except OSError as e:  # the client went away (reset, broken pipe, shut at close)
            log.debug("camera client %s:%s gone: %s", *self.client_address, e)

    def _stream(self) -> None:
        board = self.server.board
        board.count_client(+1)
        try:
            self.send_response(200)
            self.send_header("Content-Type", f"multipart/x-mixed-replace; boundary={BOUNDARY}")
            self.send_header("Cache-Control", "no-cache, no-store")
            self.send_header("Pragma", "no-cache")
            self.end_headers()
            seq = 0
            while (part := board.wait_next(seq)) is not None:
                seq, jpeg = part
                head = (f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\n"
                        f"Content-Length: {len(jpeg)}\r\n\r\n").encode("ascii")
                self.wfile.write(head + jpeg + b"\r\n")
        finally:
            board.count_client(-1)

    def _snapshot(self) -> None:
        jpeg = self.server.board.newest()
        if jpeg is None:
            self.send_error(503, "no frame yet")
            return
        self.send_response(200)
        self.send_header("Content-Type", "image/jpeg")
        self.send_header("Content-Length", str(len(jpeg)))
        self.send_header("Cache-Control", "no-cache, no-store")
        self.end_headers()
        self.wfile.write(jpeg)

    def log_message(self, format: str, *args: object) -> None:
        log.debug("camera client %s: " + format, self.address_string(), *args)


class CameraServer:
    """MJPEG over HTTP of the frames given to :meth:`publish` (see the module rules).

    Serves from construction until :meth:`close`.

    Args:
        host: address to bind (``127.0.0.1``: this machine only; ``0.0.0.0``: every
            interface).
        port: TCP port; 0 picks a free one (see :attr:`port`).
        jpeg_quality: cv2.IMWRITE_JPEG_QUALITY, 1-100.

    Raises:
        ValueError: ``jpeg_quality`` outside 1-100.
        TransportError: the address cannot be bound (in use, not local, bad name).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 jpeg_quality: int = DEFAULT_JPEG_QUALITY) -> None:
        if not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be in 1..100, got {jpeg_quality}")
        self.host = host
        self._board = _FrameBoard(jpeg_quality)
        try:
            self._http = _HttpServer((host, port), self._board)
        except OSError as e:
            raise TransportError(f"http:{host}:{port}",
                                 f"cannot listen: {e.strerror or e}") from None
        self._thread = threading.Thread(target=self._http.serve_forever, args=(_POLL_S,),
                                        name="camera-server")
        self._thread.start()
        self._closed = False

    def __enter__(self) -> CameraServer:
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
        return f"http://{self.host}:{self.port}{STREAM_PATH}"

    @property
    def snapshot_url(self) -> str:
        """The newest frame as one JPEG."""
        return f"http://{self.host}:{self.port}{SNAPSHOT_PATH}"

    def publish(self, t_ns: int, image: npt.NDArray[np.uint8]) -> None:
        """A new frame for every client (rule 1); never waits for a client.

        Args:
            t_ns: exposure time, ns (frame time: what :meth:`stall` measures).
            image: (H, W) uint8 grey or (H, W, 3) uint8 BGR; kept, not copied, so the
                caller must not modify it afterwards.

        Raises:
            ShapeError: ``image`` is neither.
        """
        if image.dtype != np.uint8 or not (image.ndim == 2 or image.shape[2:] == (3,)):
            raise ShapeError(f"image: expected (H, W) or (H, W, 3) uint8, got {image.shape} "
                             f"{image.dtype}")
        self._board.publish(t_ns, image)

    def stall(self, duration_ns: int) -> None:
        """Withhold the frames from the newest one published until ``duration_ns`` later
        in frame time (replaces a stall in progress); clients stay connected."""
        self._board.stall(duration_ns)

    def corrupt(self, count: int) -> None:
        """Send the next ``count`` frames delivered as bytes that are not a JPEG."""
        self._board.corrupt(count)

    def stats(self) -> CameraServerStats:
        """The counts so far."""
        return self._board.stats()

    def close(self) -> None:
        """Drop every client, stop serving and join the threads (rule 3); idempotent."""
        if self._closed:
            return
        self._closed = True
        self._http.shutdown()
        self._board.close()
        self._http.drop_all()
        self._http.server_close()
        self._thread.join()


class CameraFeed:
    """Films a :class:`~sim.simulation.Simulation` for a :class:`CameraServer`.

    A step hook (``sim.add_step_hook(feed)``): at the first step and then every
    ``SimConfig.frame_period_ns`` of simulation time, on the physics step grid, it
    renders the robot's camera and publishes the frame. Rendering runs in the loop
    thread, where the simulation may be read safely; an 800x600 frame takes about
    7 ms, so the ARIA I/O of that tick is late by as much, well inside the 100 ms
    SIP cycle.

    Args:
        sim: the simulation to film (the one the emulated Pioneer drives).
        camera: the simulated lens.
        server: where the frames go.

    Attributes:
        last: the last rendered frame with its ground truth (None before the first);
            for evaluation and tests, clients see the JPEG.
        frames: frames rendered so far.
    """

    def __init__(self, sim: Simulation, camera: CameraModel, server: CameraServer) -> None:
        self._sim = sim
        self._renderer = FisheyeRenderer.for_simulation(sim, camera)
        self._server = server
        self._next_ns: int | None = None
        self.last: RenderedFrame | None = None
        self.frames = 0

    def __call__(self, now_ns: int, dt_ns: int) -> None:
        if self._next_ns is None:
            self._next_ns = now_ns
        if now_ns < self._next_ns:
            return
        self._next_ns += self._sim.config.frame_period_ns
        frame = self._renderer.render(self._sim)
        self.last = frame
        self.frames += 1
        self._server.publish(frame.t_ns, frame.image)
