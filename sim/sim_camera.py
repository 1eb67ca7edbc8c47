"""The simulated camera as a :class:`shared.interfaces.FrameSource`, in lock-step.

A real camera's ``read`` blocks until the next exposure; here the next exposure is
one ``SimConfig.frame_period_ns`` after the previous one (the first at the time of
the first read), and waiting for it is sleeping on the :class:`sim.sim_clock.SimClock`,
which steps the physics. A loop that already slept to the exposure time waits no
further. Frames are rendered by :class:`sim.renderer.FisheyeRenderer`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from sim.renderer import FisheyeRenderer, RenderedFrame
from sim.sim_clock import SimClock
from sim.simulation import Simulation


class SimFrameSource:
    """Frames of the simulated robot's camera, one per frame period.

    Args:
        sim: the simulation to film.
        camera: the simulated lens.
        clock: the lock-step clock of ``sim`` (waiting for an exposure steps the world).

    Attributes:
        last: the last rendered frame with its ground truth (None before the first
            read); for evaluation and display only, the robot sees ``read()``.
    """

    def __init__(self, sim: Simulation, camera: CameraModel, clock: SimClock) -> None:
        self._sim = sim
        self._clock = clock
        self._renderer = FisheyeRenderer.for_simulation(sim, camera)
        self._next_ns: int | None = None
        self.last: RenderedFrame | None = None

    def read(self) -> tuple[int, npt.NDArray[np.uint8]]:
        """Wait for the next exposure and render it.

        Returns:
            ``(t_ns, image)``: simulation time of the exposure, ns, and the (H, W)
            uint8 grey frame. The simulated camera never ends.
        """
        if self._next_ns is not None:
            self._clock.sleep_until_ns(self._next_ns)
        frame = self._renderer.render(self._sim)
        self._next_ns = frame.t_ns + self._sim.config.frame_period_ns
        self.last = frame
        return frame.t_ns, frame.image

    def read_within(self, timeout_ns: int) -> tuple[int, npt.NDArray[np.uint8]]:
        """:meth:`read`: the simulated camera never stalls, so ``timeout_ns`` never runs
        out (the robot process's frame source, ``robot.process.TimedFrameSource``)."""
        return self.read()
