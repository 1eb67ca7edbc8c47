"""The robot's live topics over the Foxglove WebSocket protocol (``vmnav robot --foxglove``).

Foxglove and Lichtblick connect to the server this module starts (the ``foxglove-sdk``
package's; WebSocket subprotocol ``foxglove.sdk.v1``) and see the robot as its field log
records it: the same topics and the same JSON schemas (:mod:`shared.logs.topics`,
:mod:`shared.logs.schemas`), live. docs/foxglove.md shows them with the project's layout.

Rules:

1. **The loop never waits.** The loop's calls store references and return, without a
   lock or a system call (waking a thread through an Event costs the waker about 13 us
   on the development machine; ``vmnav bench foxglove`` times these calls):
   :meth:`FoxgloveBridge.offer` (every frame, with the runtime's telemetry after its
   step) puts the frame in a one-place slot, where a newer frame replaces one not yet
   taken; the :class:`~robot.runtime_log.RuntimeLog`
   calls (mission cycles, events, notes) go on a bounded deque, which drops its oldest
   when full (counted: ``dropped``). One publisher thread takes them every
   :data:`POLL_NS` and builds and encodes the messages; the SDK's server queues them per
   client and drops a slow client's oldest (``FoxgloveConfig.client_backlog_messages``).
   Frames are not copied: the camera gives each frame its own array, which nobody
   writes afterwards.
2. **Topics.** For each frame taken: :data:`~shared.logs.topics.TF` (the odometry
   ``odom`` -> ``base_link`` and the camera mount ``base_link`` -> ``camera``) and
   :data:`~shared.logs.topics.CMD_VEL` (what the runtime commanded: source ``servo`` on a
   following cycle, ``teleop`` in MANUAL, else ``stop``); at most one image per
   ``FoxgloveConfig.frame_period_ns`` of frame time: :data:`~shared.logs.topics.CAMERA_IMAGE`
   (JPEG) and :data:`~shared.logs.topics.CAMERA_ANNOTATIONS` (a mission cycle's corners
   and label as the field log draws them; on other frames the mode). For each mission
   cycle: :data:`~shared.logs.topics.SERVO_STATE` (:func:`robot.field_log.servo_state`)
   and :data:`~shared.logs.topics.BASE_STATE`. Mission events and the runtime's notes:
   :data:`~shared.logs.topics.LOG`. What only replay reads (mission starts, MAVLink)
   stays in the field log.
3. **Nothing is built for nobody:** a topic no client subscribes to costs one check
   (``Channel.has_sinks``), so a bridge without viewers encodes no JPEG.
4. **Time:** the Foxglove timestamps and the messages' log times are Unix time, the loop
   clock's ``t_ns`` plus ``unix_offset_ns``, as in the field log; the ``stamp_ns`` fields
   keep the loop's clock.
"""

from __future__ import annotations

import collections
import logging
import threading
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import cv2
import foxglove
import numpy as np
import numpy.typing as npt

from robot.config import FoxgloveConfig, VmnavConfig
from robot.field_log import (
    EVENT_SOURCE,
    NOTE_SOURCE,
    camera_transform,
    event_line,
    frame_label,
    note_level,
    servo_state,
)
from robot.mission_run import AppEvent, CycleRecord
from robot.vehicle.app_port import VehicleTelemetry
from robot.video import FramePacer
from shared.clock import NS_PER_S
from shared.config import CameraMountConfig
from shared.errors import TransportError
from shared.logs import messages, schemas, topics
from shared.mavlink.modes import Mode
from shared.pose import Pose2

log = logging.getLogger(__name__)

#: Mission cycles, events and notes queued for the publisher at most (rule 1): two
#: seconds of cycles at 30 frames/s.
QUEUE_ITEMS = 64
#: The publisher takes what the loop left this often, ns (rule 1): the delay it adds.
POLL_NS = 10_000_000
#: Colour of the corners drawn on the image (the field log's).
GREEN: messages.Rgba = (0.1, 0.9, 0.2, 1.0)
#: The channels: topic -> schema.
CHANNELS: dict[str, schemas.Schema] = {
    topics.CAMERA_IMAGE: schemas.COMPRESSED_IMAGE,
    topics.CAMERA_ANNOTATIONS: schemas.IMAGE_ANNOTATIONS,
    topics.TF: schemas.FRAME_TRANSFORMS,
    topics.CMD_VEL: schemas.COMMAND,
    topics.SERVO_STATE: schemas.SERVO_STATE,
    topics.BASE_STATE: schemas.BASE_STATE,
    topics.LOG: schemas.LOG,
}


class _Frame(NamedTuple):
    t_ns: int
    image: npt.NDArray[np.uint8]
    telemetry: VehicleTelemetry


class _Cycle(NamedTuple):
    record: CycleRecord


class _Line(NamedTuple):
    t_ns: int
    level: str
    text: str
    name: str


def command_of(frame_t_ns: int, telemetry: VehicleTelemetry,
               cycle: CycleRecord | None) -> dict[str, Any]:
    """The ``vmnav.Command`` of a frame (rule 2): the runtime's command after the frame's
    step (``telemetry.velocity``), from the servo when ``cycle`` (the frame's mission
    cycle, or None) followed the route."""
    v_m_s, omega_rad_s = telemetry.velocity
    source = ("servo" if cycle is not None and cycle.follow is not None
              else "teleop" if telemetry.mode is Mode.MANUAL else "stop")
    return {"stamp_ns": frame_t_ns, "linear_x_m_s": v_m_s, "angular_z_rad_s": omega_rad_s,
            "source": source}


def annotations_of(stamp_ns: int, telemetry: VehicleTelemetry, cycle: CycleRecord | None,
                   label: str | None) -> dict[str, Any]:
    """The ``foxglove.ImageAnnotations`` of an image at Unix time ``stamp_ns``: the corners
    of its mission cycle with ``label`` (the field log's), else no points and the mode."""
    if cycle is None:
        mode = telemetry.mode.name.lower()
        return messages.image_points(stamp_ns, np.zeros((0, 2)), GREEN, 4.0,
                                     f"{mode}, teaching" if telemetry.teaching else mode)
    follow = cycle.follow
    # OpenCV's pixel centres are at integers, Foxglove's at +0.5 (messages.image_points).
    corners = np.zeros((0, 2)) if follow is None else follow.corners_xy + 0.5
    return messages.image_points(stamp_ns, corners, GREEN, 4.0, label)


class FoxgloveBridge:
    """The Foxglove WebSocket server of the robot's live topics (module rules).

    It implements :class:`robot.runtime_log.RuntimeLog` (cycles, events, notes; teach
    frames and mission starts come through :meth:`offer` or not at all).

    Args:
        host: the address to listen on (the caller decides whether it may be off this
            machine).
        port: the TCP port; 0 picks a free one (:attr:`port` tells which).
        config: image rate, JPEG quality, per-client backlog.
        mount: the camera's mount on the base (the static ``base_link`` -> ``camera``).
        unix_offset_ns: Unix time minus the loop clock's reading, ns (rule 4).
        where: the option the address came from, for messages (``--foxglove 8765``).

    Raises:
        TransportError: the server cannot listen there (a port in use, an unknown host:
            one line naming ``where``).
    """

    def __init__(self, host: str, port: int, config: FoxgloveConfig, mount: CameraMountConfig,
                 *, unix_offset_ns: int, where: str) -> None:
        self._config = config
        self._unix_offset_ns = unix_offset_ns
        self._camera = camera_transform(mount)
        self._pacer = FramePacer(config.frame_period_ns)
        # Kept: the server does not keep its context alive, and without it advertises nothing.
        self._context = foxglove.Context()
        self._channels = {topic: foxglove.Channel(topic, schema=schema, context=self._context)
                          for topic, schema in CHANNELS.items()}
        try:
            self._server = foxglove.start_server(
                name="vmnav robot", host=host, port=port, context=self._context,
                message_backlog_size=config.client_backlog_messages)
        except RuntimeError as e:
            raise TransportError(where, f"cannot listen: "
                                        f"{str(e).removeprefix('FoxgloveError: ')}") from None
        self.host = host
        self.port = self._server.port
        self.dropped = 0
        self.errors = 0
        self._frame: _Frame | None = None
        self._published: _Frame | None = None
        self._queue: collections.deque[_Cycle | _Line] = collections.deque(maxlen=QUEUE_ITEMS)
        self._stop = threading.Event()
        self._last_cycle: CycleRecord | None = None
        self._last_label: str | None = None
        self._thread = threading.Thread(target=self._run, name="foxglove-bridge", daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        """The WebSocket URL clients open."""
        return f"ws://{self.host}:{self.port}"

    # -- the loop's side (rule 1) -------------------------------------------------------

    def offer(self, t_ns: int, image: npt.NDArray[np.uint8], telemetry: VehicleTelemetry) -> None:
        """The loop's frame at ``t_ns`` ((H, W) uint8 grey) and the runtime's telemetry
        after its step."""
        self._frame = _Frame(t_ns, image, telemetry)

    def cycle(self, record: CycleRecord, image: npt.NDArray[np.uint8]) -> None:
        """A mission cycle (its frame comes through :meth:`offer`)."""
        self._put(_Cycle(record))

    def event(self, event: AppEvent) -> None:
        """A mission event, a ``foxglove.Log`` line."""
        self._put(_Line(event.t_ns, *event_line(event), EVENT_SOURCE))

    def note(self, t_ns: int, level: int, text: str) -> None:
        """A note of the runtime (``logging`` level), a ``foxglove.Log`` line."""
        self._put(_Line(t_ns, note_level(level), text, NOTE_SOURCE))

    def teach_frame(self, t_ns: int, image: npt.NDArray[np.uint8], odom_pose: Pose2) -> None:
        """Nothing: the frame and the odometry come through :meth:`offer`."""

    def mission_started(self, t_ns: int, goal_id: int, rng_state: Any,
                        config: VmnavConfig) -> None:
        """Nothing: what replay needs stays in the field log (rule 2)."""

    def _put(self, item: _Cycle | _Line) -> None:
        if len(self._queue) == QUEUE_ITEMS:
            self.dropped += 1
        self._queue.append(item)

    # -- the publisher thread -----------------------------------------------------------

    def close(self) -> None:
        """Stop the publisher thread and the server (clients are disconnected). Idempotent."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join(5.0)
        self._server.stop()

    def __enter__(self) -> FoxgloveBridge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _run(self) -> None:
        while not self._stop.wait(POLL_NS / NS_PER_S):
            # The frame first: its cycle was queued before it (the loop's order), so it is
            # among the items taken next. One read: the loop may replace it meanwhile.
            frame = self._frame
            try:
                while self._queue:
                    item = self._queue.popleft()
                    if isinstance(item, _Cycle):
                        self._publish_cycle(item)
                    else:
                        self._publish_line(item)
                if frame is not None and frame is not self._published:
                    self._published = frame
                    self._publish_frame(frame)
            except Exception:  # a bug must not end the live topics: counted, said once
                self.errors += 1
                if self.errors == 1:
                    log.exception("foxglove bridge: a message could not be published")

    def _log(self, topic: str, t_ns: int, build: Callable[[], Mapping[str, Any]]) -> None:
        channel = self._channels[topic]
        if channel.has_sinks():
            channel.log(messages.encode_json(build()), log_time=t_ns + self._unix_offset_ns)

    def _publish_cycle(self, cycle: _Cycle) -> None:
        record = cycle.record
        state = servo_state(record)
        self._last_cycle = record
        self._last_label = frame_label(record.state.value, state["key_image_id"],
                                       state["matched_points"])
        self._log(topics.SERVO_STATE, record.t_ns, lambda: state)
        self._log(topics.BASE_STATE, record.t_ns,
                  lambda: messages.base_state_fields(record.t_ns, record.base))

    def _publish_line(self, line: _Line) -> None:
        self._log(topics.LOG, line.t_ns, lambda: messages.log_entry(
            line.t_ns + self._unix_offset_ns, line.level, line.text, line.name))

    def _publish_frame(self, frame: _Frame) -> None:
        t_ns, telemetry = frame.t_ns, frame.telemetry
        stamp_ns = t_ns + self._unix_offset_ns
        last = self._last_cycle
        cycle = last if last is not None and last.t_ns == t_ns else None
        self._log(topics.TF, t_ns, lambda: messages.frame_transforms(stamp_ns, [
            messages.FrameTransform.planar(topics.FRAME_ODOM, topics.FRAME_BASE,
                                           *telemetry.odom_pose),
            self._camera]))
        self._log(topics.CMD_VEL, t_ns, lambda: command_of(t_ns, telemetry, cycle))
        if not self._pacer.due(t_ns):
            return
        self._log(topics.CAMERA_IMAGE, t_ns, lambda: messages.compressed_image(
            stamp_ns, topics.FRAME_CAMERA, self._jpeg(frame.image)))
        self._log(topics.CAMERA_ANNOTATIONS, t_ns, lambda: annotations_of(
            stamp_ns, telemetry, cycle, self._last_label))

    def _jpeg(self, image: npt.NDArray[np.uint8]) -> bytes:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY,
                                                self._config.jpeg_quality])
        if not ok:
            raise ValueError(f"cv2.imencode failed on a {image.shape} image")
        return data.tobytes()
