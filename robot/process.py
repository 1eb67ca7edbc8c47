"""The robot process: the robot's application assembled from its parts, its loop, its end.

The real robot (``vmnav robot``, and so the HIL rig, which runs it), and the lock-step
demo (``tools/harness/demo.py``) build the robot here, from parts the caller opened:
a visual memory and its folder, a :class:`~shared.interfaces.MobileBase`, a frame
source (:class:`TimedFrameSource`), a :class:`~shared.clock.Clock`, the config, the
vehicle's files and MAVLink signing, the field log; and a MAVLink link (an address,
``shared.link_address``, that :class:`RobotProcess` opens, or its transport opened by
the caller: ``robot.vehicle.vehicle_link``). What it assembles:
:class:`robot.runtime.RobotRuntime` on the base, as the application of a
:class:`robot.vehicle.endpoint.VehicleEndpoint` on a
:class:`robot.vehicle.udp_vehicle.UdpVehicle` or
:class:`robot.vehicle.stream_vehicle.StreamVehicle` (its own I/O thread), whose traffic
goes to the field log: the MAVLink packets accepted and sent, and the counts of what was
rejected (``VehicleIo`` rule 2).

Rules:

1. **The loop** (:meth:`RobotProcess.run`) hands each frame to
   :meth:`RobotRuntime.step` (then, with a live view, to :meth:`robot.video.LiveView.offer`,
   and with live topics to :meth:`robot.foxglove_bridge.FoxgloveBridge.offer`, neither of
   which waits) and, when no frame comes within
   ``TeleopConfig.frame_timeout_ns``, tells it the camera stalled
   (:meth:`RobotRuntime.stall`: the base stops), until the camera ends, the loop's
   clock reaches ``end_ns``, the caller's ``on_step`` says :attr:`AfterStep.STOP`, or
   :meth:`RobotProcess.stop` was called (from any thread or a signal handler; the loop
   sees it before its next frame, within a frame period or the frame timeout).
   The real robot is paced by its camera; a lock-step loop gives a ``period_ns`` and
   sleeps on the clock to each next deadline, which steps the simulation.
2. **Holding the clock** (lock-step only): ``on_step`` answering
   :attr:`AfterStep.HOLD_CLOCK` makes the loop wait :data:`HOLD_POLL_NS` on the link's
   clock and step the same frame again, without moving the loop's clock. That is how a
   lock-step run waits for the world outside the simulation (a ground station in wall
   time) while the robot stands still: what the simulation does cannot depend on how
   fast the outside answers, so every run gives the same figures. The same frame again
   is harmless only while nothing consumes frames (no mission run, no teaching).
3. **Two clocks.** The loop's ``clock`` stamps frames, the runtime and the field log.
   The link's I/O thread runs on ``link_clock`` (the same clock on the robot; the wall
   clock in lock-step, where the ground station is outside the simulation). MAVLink
   in and out is logged on the loop's clock: at the I/O round's time when both
   clocks are one, else at the loop clock's reading as the packet passes. The GCS
   failsafe times the ground's silence on the link's clock, and in lock-step on the
   loop's too: lost only when silent on both (``robot.vehicle.failsafe`` rule 5).
4. **Closing** (:meth:`RobotProcess.close`, or leaving its ``with`` block; also when
   opening the link fails) goes in the order the field log needs: the link (no
   request comes in any more), the runtime (the base stops, a mission run ends as the
   operator's abort, the worker finishes its job), the parts handed over in ``owned``
   (the Pioneer's driver sends its CLOSE, the camera stops), then ``log_end`` (the
   field log records how the Pioneer link ended), and the field log is finished last.

Replay (:mod:`robot.replay`) does not run this process: it reruns logged mission runs
alone, from logged inputs, and shares with the runtime how a mission run is built
(:func:`robot.mission_run.start_run`).
"""

from __future__ import annotations

import contextlib
import enum
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from robot.camera import Frame, FrameStall
from robot.config import VmnavConfig
from robot.field_log import FieldLog
from robot.mission_run import CycleRecord
from robot.runtime import RobotRuntime
from robot.runtime_log import RuntimeLog, RuntimeLogs
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.vehicle_io import Rejected
from robot.vehicle.vehicle_link import VehicleTransport, open_vehicle_transport, vehicle_on
from robot.video import LiveView, video_stream
from shared.clock import Clock
from shared.interfaces import MobileBase
from shared.memory import VisualMemory

if TYPE_CHECKING:  # the SDK is imported only by a robot that serves Foxglove
    from robot.foxglove_bridge import FoxgloveBridge

#: While the loop holds the clock (rule 2), it steps the same frame again this often on
#: the link's clock, ns.
HOLD_POLL_NS = 2_000_000

CAMERA_ENDED = "the camera ended"
TIME_UP = "the time given ran out"
STOPPED = "its caller stopped it"


class TimedFrameSource(Protocol):
    """Camera frames that may stall: :class:`robot.camera.VideoCaptureSource`, or a
    simulated camera (which never stalls)."""

    def read_within(self, timeout_ns: int) -> Frame | FrameStall | None:
        """The next frame, waiting at most ``timeout_ns`` (real time).

        Returns:
            ``(t_ns, image)``: the frame's time on the loop's clock, ns, and the (H, W)
            uint8 grey image; a :class:`~robot.camera.FrameStall` when none came in time
            (frames may return); None when no frame will come.
        """
        ...


class AfterStep(enum.Enum):
    """What the loop does after a frame's step (the answer of ``on_step``)."""

    NEXT_FRAME = enum.auto()  #: go on: sleep to the next deadline, read the next frame
    HOLD_CLOCK = enum.auto()  #: lock-step: step the same frame again, the clock held (rule 2)
    STOP = enum.auto()  #: end the loop


OnStep = Callable[[CycleRecord | None], AfterStep]
"""Called after each frame's step with the mission cycle it ran (None: no mission run)."""


@dataclass(frozen=True, eq=False)
class RobotParts:
    """What the robot process is assembled from (opened by the caller).

    Attributes:
        memory: the visual memory, as loaded from ``files.memory_dir`` (or empty).
        base: the mobile base (the Pioneer's driver, connected).
        frames: the camera.
        clock: the loop's clock: frames are stamped on it (rule 3).
        config: every component's settings.
        files: the memory's folder (taught paths are written there, served over FTP),
            the upload folder and the parameter file.
        rng: seeds each mission run's generator.
        log: the field log; None records nothing.
        signing: MAVLink 2 signing of the link; None: unsigned.
        link_warning: told to every ground station that connects (``vmnav robot
            --insecure``); None: nothing.
        lockstep: the clock is a simulation's (the runtime's worker results land on
            the next frame; the loop may hold the clock).
        video: the live view (``vmnav robot --video``): offered every frame (rule 1) and
            advertised by the vehicle's camera component; None: no live view, no camera
            component.
        foxglove: the live topics (``vmnav robot --foxglove``): offered every frame with
            the telemetry (rule 1), and the runtime records to it as to the field log;
            None: not served.
    """

    memory: VisualMemory
    base: MobileBase
    frames: TimedFrameSource
    clock: Clock
    config: VmnavConfig
    files: VehicleFiles
    rng: np.random.Generator
    log: FieldLog | None = None
    signing: SigningSetup | None = None
    link_warning: str | None = None
    lockstep: bool = False
    video: LiveView | None = None
    foxglove: FoxgloveBridge | None = None


class RobotProcess:
    """The robot's runtime as a MAVLink vehicle on ``link``, fed by ``parts.frames``
    (module rules).

    Args:
        parts: what the robot is made of; the process owns ``parts.log`` from now on.
        link: the ground link: its address (``udpin:127.0.0.1:14550`` waits for a
            ground station, ``udpout:HOST:14550`` calls one, ``serial:/dev/ttyUSB0:57600``
            is a telemetry radio...), or its transport, opened; the process owns it.
        link_clock: the link's I/O clock (rule 3); None: ``parts.clock``.
        owned: parts the caller opened and hands over, closed after the runtime
            (rule 4); None: none.
        log_end: called with ``parts.log`` once they are closed, before the log is
            finished (rule 4); not called without a log.

    Raises:
        InputError: ``link`` is not an address (what the process owns is closed first).
        TransportError: ``link``'s port is taken or its device missing (the same).
    """

    def __init__(self, parts: RobotParts, link: str | VehicleTransport, *,
                 link_clock: Clock | None = None,
                 owned: contextlib.ExitStack | None = None,
                 log_end: Callable[[FieldLog], None] | None = None) -> None:
        self._frames = parts.frames
        self._clock = parts.clock
        self._link_clock = parts.clock if link_clock is None else link_clock
        self._lockstep = parts.lockstep
        self._frame_timeout_ns = parts.config.teleop.frame_timeout_ns
        self._stop = threading.Event()
        self._stop_why = STOPPED
        undo = contextlib.ExitStack()
        with undo:  # unwinds only when something below raises
            log = parts.log
            if log is not None:
                undo.callback(log.close)
                if log_end is not None:
                    undo.callback(log_end, log)
            if owned is not None:
                undo.push(owned)
            self._foxglove = parts.foxglove
            records: list[RuntimeLog] = [r for r in (log, parts.foxglove) if r is not None]
            self.runtime = RobotRuntime(parts.memory, parts.files.memory_dir, parts.config,
                                        parts.base, parts.clock, parts.rng,
                                        log=RuntimeLogs(*records) if records else None,
                                        lockstep=parts.lockstep)
            undo.callback(self.runtime.close)
            self._video = parts.video
            stream = None if parts.video is None else video_stream(
                parts.video.server, parts.config.video, parts.memory.camera)
            transport = open_vehicle_transport(link) if isinstance(link, str) else link
            undo.callback(transport.close)
            endpoint = VehicleEndpoint(self.runtime, parts.config, parts.files,
                                       signing=parts.signing,
                                       link_warning=parts.link_warning, video=stream,
                                       failsafe_clock=parts.clock if parts.lockstep else None)
            self.vehicle = undo.enter_context(vehicle_on(transport, endpoint,
                                                         self._link_clock))
            if log is not None:
                self.vehicle.packet_taps.append(self._mavlink_tap(log))
                self.vehicle.reject_observers.append(self._reject_observer(log))
            self.vehicle.start_thread()
            self._closing = undo.pop_all()

    def __enter__(self) -> RobotProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def run(self, *, end_ns: int | None = None, period_ns: int | None = None,
            on_step: OnStep | None = None) -> str:
        """The loop (rule 1): frames to the runtime until the camera ends, ``end_ns``, or
        ``on_step`` stops it.

        Args:
            end_ns: stop once the loop's clock reaches this, ns; None: no time limit.
            period_ns: lock-step: sleep on the clock to a deadline this much later after
                each frame, ns (steps the simulation); None: the camera paces the loop.
            on_step: the caller's look at each frame's step; None: always the next frame.

        Returns:
            Why it stopped: :data:`CAMERA_ENDED`, :data:`TIME_UP`, :data:`STOPPED`, or
            what :meth:`stop` was told.

        Raises:
            ValueError: ``on_step`` held the clock of a process that is not lock-step.
        """
        runtime, clock = self.runtime, self._clock
        deadline_ns = clock.now_ns()
        while end_ns is None or clock.now_ns() < end_ns:
            if self._stop.is_set():
                return self._stop_why
            frame = self._frames.read_within(self._frame_timeout_ns)
            if frame is None:
                return CAMERA_ENDED
            if isinstance(frame, FrameStall):
                runtime.stall(frame.t_ns)
                continue
            after = self._step(frame, on_step)
            if after is AfterStep.STOP:
                return STOPPED
            if period_ns is not None:
                deadline_ns += period_ns
                clock.sleep_until_ns(deadline_ns)
        return TIME_UP

    def stop(self, why: str = STOPPED) -> None:
        """Ask the loop to end before its next frame, saying ``why``; safe from another
        thread or a signal handler (it sets a flag and never waits)."""
        self._stop_why = why
        self._stop.set()

    def _step(self, frame: Frame, on_step: OnStep | None) -> AfterStep:
        """Step ``frame``, again while ``on_step`` holds the clock (rule 2); what then."""
        record = self.runtime.step(*frame)
        if self._video is not None:
            servo = self.runtime.telemetry().servo
            self._video.offer(*frame, record, None if servo is None else servo.next_key)
        if self._foxglove is not None:
            self._foxglove.offer(*frame, self.runtime.telemetry())
        if on_step is None:
            return AfterStep.NEXT_FRAME
        after = on_step(record)
        while after is AfterStep.HOLD_CLOCK:
            if not self._lockstep:
                raise ValueError("only a lock-step process can hold its clock")
            self._link_clock.sleep_until_ns(self._link_clock.now_ns() + HOLD_POLL_NS)
            after = on_step(self.runtime.step(*frame))
        return after

    def close(self) -> None:
        """Close in the order of rule 4; idempotent."""
        self._closing.close()

    def _reject_observer(self, log: FieldLog) -> Callable[[Rejected, int], None]:
        """The field log's counts of rejected MAVLink traffic, on the loop's clock (rule 3)."""
        same = self._link_clock is self._clock
        clock = self._clock

        def observe(rejected: Rejected, t_ns: int) -> None:
            log.mavlink_rejected(t_ns if same else clock.now_ns(), rejected.unverified,
                                 rejected.shed, rejected.period_ns)
        return observe

    def _mavlink_tap(self, log: FieldLog) -> Callable[[str, bytes, int], None]:
        """The field log's MAVLink in and out, on the loop's clock (rule 3)."""
        if self._link_clock is self._clock:
            return lambda way, data, t_ns: log.mavlink(t_ns, way, data)
        clock = self._clock
        return lambda way, data, _: log.mavlink(clock.now_ns(), way, data)
