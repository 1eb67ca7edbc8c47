"""The simulator's network camera: its rendered frames as MJPEG over HTTP (issue 8).

The robot reads it like a real network camera, through ``cv2.VideoCapture(URL)``. The
serving itself (frames in from the simulation loop, encoded in the clients' threads,
a client that falls behind skipping to the newest frame, hostile clients, the stall and
corrupt faults) is :class:`shared.mjpeg_server.MjpegServer`'s, which the robot's live
view (``vmnav robot --video``) shares; here are its simulator defaults and
:class:`CameraFeed`, the step hook that films the simulation for it.
"""

from __future__ import annotations

from shared.camera_model import CameraModel
from shared.mjpeg_server import MAX_CLIENTS, SNAPSHOT_PATH, STREAM_PATH, MjpegServer, MjpegStats
from sim.config import SensorConfig
from sim.renderer import FisheyeRenderer, RenderedFrame
from sim.simulation import Simulation

__all__ = ["DEFAULT_JPEG_QUALITY", "MAX_CLIENTS", "SNAPSHOT_PATH", "STREAM_PATH", "CameraFeed",
           "CameraServer", "CameraServerStats"]

DEFAULT_JPEG_QUALITY = SensorConfig().jpeg_quality
"""cv2.IMWRITE_JPEG_QUALITY of the served frames unless told (``[sim.sensor]
jpeg_quality``: the simulated camera's MJPEG)."""

CameraServerStats = MjpegStats


class CameraServer(MjpegServer):
    """The simulated camera's :class:`~shared.mjpeg_server.MjpegServer`: frames at their
    rendered size, JPEG at the simulated sensor's quality unless told.

    Args:
        host: address to bind (``127.0.0.1``: this machine only; ``0.0.0.0``: every
            interface).
        port: TCP port; 0 picks a free one.
        jpeg_quality: cv2.IMWRITE_JPEG_QUALITY, 1-100.

    Raises:
        ValueError: ``jpeg_quality`` outside 1-100.
        TransportError: the address cannot be bound (in use, not local, bad name).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 jpeg_quality: int = DEFAULT_JPEG_QUALITY) -> None:
        super().__init__(host, port, jpeg_quality)


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
