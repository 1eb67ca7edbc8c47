"""The camera part of ``vmnav bench web``: the robot's live view at 640x480 in the page.

The robot side is the robot's own: :class:`robot.video.LiveView` paced by a
:class:`~robot.config.VideoConfig` (640 wide, ``--camera-hz`` frames/s), serving through
:class:`~shared.mjpeg_server.MjpegServer`, advertised by vehicle 1's camera component
(the MAVLink camera protocol), relayed by the ground station
(``ground.web.camera_proxy``) to the page's ``<img>``. The frames are synthetic (a
textured 640x480 grey image, the size of the issue's figure) and each carries its number
drawn as :data:`BITS` black or white blocks across its top: the camera loop offers one
every :data:`CAMERA_PERIOD_NS` and notes the wall time it did.

The page side reads the number back from the image the page shows: every 4 ms a script
draws the top of ``#camera-image`` onto a canvas, decodes the blocks, and notes the wall
time (``performance.timeOrigin + performance.now()``) when a new number appears. So
``latency_ms`` is from the frame handed to the robot's server to the page showing it
(encoding, the robot's HTTP, the relay, the browser's decoding; plus up to 4 ms of
sampling), one wall clock for both ends; ``shown_fps`` is the distinct frames the page
showed per second over the window. A number read that was never sent (a misread) is
counted, not timed.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import numpy.typing as npt

from robot.config import VideoConfig
from robot.video import LiveView
from shared.clock import NS_PER_S, WallClock
from shared.mavlink.camera import VideoStream
from shared.mjpeg_server import MjpegServer
from tools.bench.percentiles import percentile_summary

#: The issue's figures (figure -> comparison, bound).
TARGETS: dict[str, tuple[str, float]] = {
    "camera.shown_fps": (">=", 10.0), "camera.latency_ms.p95": ("<", 250.0),
    "camera.misread": ("<=", 0)}
#: (W, H) of the frames, px.
SIZE = (640, 480)
#: The camera's own rate: frames offered to the live view, which passes ``--camera-hz``.
CAMERA_PERIOD_NS = NS_PER_S // 30
#: Bits of the frame number, each a block of :data:`BLOCK_W` x :data:`BLOCK_H` px.
BITS = 16
BLOCK_W, BLOCK_H = SIZE[0] // BITS, 24

#: The page's sampler: ``window.benchFrames`` gets [number, wall ms] per new number.
SAMPLER_JS = f"""
window.benchFrames = [];
const img = document.getElementById('camera-image');
const canvas = document.createElement('canvas');
canvas.width = {SIZE[0]}; canvas.height = {BLOCK_H};
const ctx = canvas.getContext('2d', {{willReadFrequently: true}});
let last = -1;
window.benchSampler = setInterval(() => {{
  if (img.naturalWidth !== {SIZE[0]}) return;
  ctx.drawImage(img, 0, 0, {SIZE[0]}, {BLOCK_H}, 0, 0, {SIZE[0]}, {BLOCK_H});
  const data = ctx.getImageData(0, 0, {SIZE[0]}, {BLOCK_H}).data;
  let n = 0;
  for (let b = 0; b < {BITS}; b++) {{
    const i = ({BLOCK_H // 2} * {SIZE[0]} + b * {BLOCK_W} + {BLOCK_W // 2}) * 4;
    n = n * 2 + (data[i] > 127 ? 1 : 0);
  }}
  if (n !== last) {{
    last = n;
    window.benchFrames.push([n, performance.timeOrigin + performance.now()]);
  }}
}}, 4);
"""


def numbered_frame(number: int, texture: npt.NDArray[np.uint8]) -> npt.NDArray[np.uint8]:
    """``texture`` (H, W) uint8 with ``number`` (0 .. 2**BITS - 1) as blocks across its top,
    most significant bit left: white (255) for 1, black for 0."""
    frame = texture.copy()
    for b in range(BITS):
        bit = (number >> (BITS - 1 - b)) & 1
        frame[:BLOCK_H, b * BLOCK_W:(b + 1) * BLOCK_W] = 255 if bit else 0
    return frame


class CameraRobot:
    """The robot's live view of numbered frames, offered at the camera's rate by a thread.

    Args:
        rate_hz: the live view's rate (``VideoConfig.frame_period_ns``), frames/s.
    """

    def __init__(self, rate_hz: float) -> None:
        self.config = VideoConfig(width_px=SIZE[0], frame_period_ns=round(NS_PER_S / rate_hz))
        self.server = MjpegServer(width_px=self.config.width_px,
                                  jpeg_quality=self.config.jpeg_quality,
                                  max_clients=self.config.max_clients)
        self.stream = VideoStream(self.server.stream_url, *SIZE, rate_hz)
        self.sent_ms: dict[int, float] = {}
        """Frame number -> wall time it was offered, ms."""
        self._view = LiveView(self.server, self.config)
        self._texture = np.random.default_rng(0).integers(60, 200, SIZE[::-1]).astype(np.uint8)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="bench-camera", daemon=True)

    def _run(self) -> None:
        clock = WallClock()
        deadline_ns = clock.now_ns()
        number = 0
        while not self._stop.is_set():
            frame = numbered_frame(number % (1 << BITS), self._texture)
            self.sent_ms[number % (1 << BITS)] = time.time() * 1000
            self._view.offer(deadline_ns, frame, None)
            number += 1
            deadline_ns += CAMERA_PERIOD_NS
            clock.sleep_until_ns(deadline_ns)

    @contextmanager
    def running(self) -> Iterator[CameraRobot]:
        """Offer frames until the block ends; then stop and close the server."""
        self._thread.start()
        try:
            yield self
        finally:
            self._stop.set()
            self._thread.join()
            self.server.close()


def camera_figures(shown: list[list[float]], sent_ms: dict[int, float],
                   window_s: float) -> dict[str, Any]:
    """The JSON figures from the page's ``[number, wall ms]`` list (module docstring).

    Args:
        shown: what the sampler noted, in order.
        sent_ms: frame number -> wall time offered, ms.
        window_s: the time the page was watched, s.
    """
    known = [(int(n), t) for n, t in shown if int(n) in sent_ms]
    latencies = [t - sent_ms[n] for n, t in known]
    span_s = (known[-1][1] - known[0][1]) / 1000 if len(known) >= 2 else 0.0
    return {"size": list(SIZE), "window_s": round(window_s, 2), "frames_shown": len(known),
            "shown_fps": round((len(known) - 1) / span_s, 2) if span_s > 0 else 0.0,
            "latency_ms": percentile_summary(latencies), "misread": len(shown) - len(known)}
