"""VehicleEndpoint: the robot as a MAVLink vehicle, sans-I/O (bytes in, packets out).

Theory of operation
-------------------

The endpoint composes the shared protocol cores behind one surface::

    endpoint.receive(datagram, now_ns)      # any number of MAVLink packets
    for packet in endpoint.poll(now_ns):    # everything due now, one packet each
        transport.send(packet)
    endpoint.get_timer()                    # when poll has something to do next, ns

and talks to the robot only through :class:`~robot.vehicle.app_port.VehicleApp`.

Rules:

1. Identity: system ``MavlinkConfig.system_id``, component 1 (QGC and MAVSDK want
   an autopilot there), HEARTBEAT as a generic-autopilot ground rover every
   ``heartbeat_period_ns`` with ArduRover mode numbers (``shared.mavlink.modes``), and
   one more at once when the mode or the armed state changes (a ground station shows the
   change within a poll, not up to a period later).
2. Received packets go to the cores: commands (``shared.mavlink.commands.vehicle``, plus
   the user commands of ``user_commands``), missions, parameters, FTP over the
   memory and upload area (``robot.vehicle.ftp_memory``); HEARTBEATs of ground
   stations feed the failsafe; MANUAL_CONTROL, SET_MODE and TIMESYNC are handled
   here. Replies wait in an outbox for the next :meth:`poll`. Every message is
   checked before use (the cores check theirs): a MANUAL_CONTROL with an axis
   outside -1000..1000 (INT16_MAX: unused) or a SET_MODE naming no mode is dropped.
3. Modes: DO_SET_MODE (ArduPilot or PX4 encoding) and SET_MODE go to
   ``VehicleApp.set_mode``, except AUTO, which (like MISSION_START) starts the
   uploaded mission from its current item through ``VehicleApp.start_mission``;
   without a mission AUTO is DENIED.
4. Missions are goal items (``shared.mavlink.mission.goal``), validated on upload by
   ``VehicleApp.validate_goals``; a refused upload keeps the mission in force. While
   the uploaded mission runs, uploads and clears are refused (MAV_MISSION_DENIED):
   switch to HOLD first. An upload is refused at its MISSION_COUNT, before any item is
   requested, and again at its end if the mission started meanwhile. The protocol would
   allow an atomic replacement, but the run drives to the goals it started with: a
   new mission in the store would make MISSION_CURRENT and a download describe goals
   the robot is not driving to.
5. Parameters are ``robot_params`` over the config; the parameter file is applied
   on construction and rewritten atomically after every change, and the
   application gets the new config (``params_changed``), at construction too.
6. Telemetry streams by default (``telemetry.default_periods_ns``), adjustable
   with SET_MESSAGE_INTERVAL; REQUEST_MESSAGE answers any of them, and
   AUTOPILOT_VERSION. Mission progress and outcomes go out as MISSION_ITEM_REACHED,
   MISSION_CURRENT and VISUAL_SERVO_STATUS, and as STATUSTEXT for people
   (``progress``); the application's notices
   (``VehicleApp.next_notice``) as STATUSTEXT at their level's severity.
   SYS_STATUS counts what went wrong on reception (:meth:`stats`), each capped at
   65535: ``errors_comm`` the corrupt packets and the datagrams the transport dropped
   unparsed (:attr:`VehicleEndpoint.shed_datagrams`), ``errors_count1`` the handler
   faults (rule 9), ``errors_count2`` the messages refused (rule 9).
7. GCS failsafe (``failsafe``): reported as STATUSTEXT, HEARTBEAT status CRITICAL
   while lost. The silence is timed on the ``now_ns`` the I/O thread gives (the link's
   clock), and also on ``failsafe_clock`` when one is given (a lock-step robot's
   simulated time): lost only when silent on both (``failsafe`` rule 5), so neither a
   process starved of CPU (a loaded sweep worker) nor a simulation running faster than
   real time finds its own ground station silent. A ``link_warning`` (``vmnav robot --insecure``:
   unsigned and open to the network) goes out as a STATUSTEXT WARNING to every ground
   station that connects: with the first GCS HEARTBEAT, and again each time the link is
   regained.
8. Signing (when a :class:`SigningSetup` is given): every packet out is signed;
   packets in that are unsigned (except RADIO_STATUS from a radio modem), wrongly
   signed or replayed are dropped and counted (:meth:`stats`); a wrongly signed packet
   moves no timestamp (``shared.mavlink.signing.check_signature``). Every
   :data:`SIGNING_PERIOD_NS` the outgoing timestamp is raised to the wall clock
   (``SigningClock``) and, with a ``timestamp_file``, the timestamps (ours and each
   stream's) are written to it atomically; also at :meth:`close`. They are read back
   on construction (and written once, so a place that cannot hold them fails at
   start), so after a restart no packet accepted before it is accepted again (after a
   crash, none accepted more than a period before it). A write that fails later is a
   STATUSTEXT ERROR, once.
9. Hostile input: a message is refused when it is answered with an error (MISSION_ACK
   other than ACCEPTED, PARAM_ERROR, COMMAND_ACK other than ACCEPTED or IN_PROGRESS)
   or dropped as malformed (rule 2); both are counted. An exception of a handler is a
   bug, but one packet must not end the link: it is counted per kind and logged once
   per kind with its traceback (:class:`~shared.handler_faults.HandlerFaults`,
   :attr:`VehicleEndpoint.faults`), the message is dropped and the next one handled.
10. The camera (``shared.mavlink.camera``; only with a ``video`` stream, ``vmnav robot
   --video``): component 100 of the same system, with its own HEARTBEAT at the
   autopilot's period, its own sequence numbers
   (:meth:`~shared.mavlink.dialect.MavlinkCodec.pack_as`) and its own command
   dispatcher, which answers the requests for CAMERA_INFORMATION,
   VIDEO_STREAM_INFORMATION and VIDEO_STREAM_STATUS addressed to it. Without a stream
   there is no camera component, and the autopilot DENIES those messages as any it
   lacks.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

from robot.config import VmnavConfig
from robot.vehicle.app_port import VehicleApp, VehicleTelemetry
from robot.vehicle.failsafe import GcsWatchdog, gcs_lost_action
from robot.vehicle.ftp_memory import MemoryFileSystem
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.param_file import load_param_file, save_param_file
from robot.vehicle.progress import MissionProgress
from robot.vehicle.robot_params import config_with_params, param_problem, robot_param_table
from robot.vehicle.telemetry import (
    TELEMETRY_BUILDERS,
    Builder,
    TelemetryStreams,
    default_periods_ns,
    sys_status_message,
    system_status,
)
from robot.vehicle.user_commands import JobCommands, user_handlers
from shared.clock import NS_PER_S, Clock
from shared.config import FtpConfig
from shared.errors import InputError
from shared.handler_faults import HandlerFaults
from shared.mavlink.address import Address, is_for
from shared.mavlink.camera import (
    CAMERA_COMPONENT_ID,
    VideoStream,
    camera_handlers,
    camera_heartbeat,
)
from shared.mavlink.commands.intervals import MessageIntervals
from shared.mavlink.commands.vehicle import (
    CommandDispatcher,
    autopilot_version_message,
    vehicle_handlers,
)
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.ftp.vehicle import FtpServer
from shared.mavlink.mission.goal import Goal, goals_from_items
from shared.mavlink.mission.items import MissionItem, MissionRefusal
from shared.mavlink.mission.vehicle import MissionServer
from shared.mavlink.modes import Mode, heartbeat_message, mode_from_set_mode
from shared.mavlink.params.vehicle import ParamChanged, ParamServer
from shared.mavlink.signing import (
    SigningClock,
    SigningStats,
    UnsignedPolicy,
    configure_signing,
    restore_timestamps,
    signing_stats,
    timestamps_of,
)
from shared.mavlink.statustext import statustext_messages
from shared.signing_timestamp_file import read_timestamp_file, write_timestamp_file

logger = logging.getLogger(__name__)

#: The vehicle's component id (MAV_COMP_ID_AUTOPILOT1).
COMPONENT_ID = 1
#: Messages accepted unsigned on a signed link: a radio modem's own reports.
UNSIGNED_ALLOWED = (mavlink.MAVLINK_MSG_ID_RADIO_STATUS,)
#: How often the signing timestamp is raised to the wall clock and kept, ns (the spec
#: asks at least once a minute).
SIGNING_PERIOD_NS = NS_PER_S
_HEARTBEAT = mavlink.MAVLINK_MSG_ID_HEARTBEAT
#: ``logging`` level of an application notice -> STATUSTEXT severity.
_SEVERITIES = {logging.DEBUG: mavlink.MAV_SEVERITY_DEBUG, logging.INFO: mavlink.MAV_SEVERITY_INFO,
               logging.WARNING: mavlink.MAV_SEVERITY_WARNING,
               logging.ERROR: mavlink.MAV_SEVERITY_ERROR,
               logging.CRITICAL: mavlink.MAV_SEVERITY_CRITICAL}
_INT16_MAX = 0x7FFF
#: MANUAL_CONTROL's axis range (common.xml), besides INT16_MAX for "axis unused".
_AXIS_LIMIT = 1000


@dataclass(frozen=True, slots=True)
class LinkStats:
    """What the endpoint received.

    Attributes:
        messages: packets decoded and handled.
        bad_packets: packets dropped as corrupt or by the signature check.
        unsigned_rejected: message id -> packets dropped for lacking a valid signature.
        signing: pymavlink's signing counters; None without signing.
        refused: messages answered with an error or dropped as malformed (rule 9).
        handler_faults: "<message type>: <exception class>" -> exceptions of handlers
            (rule 9), in the order the kinds first happened.
    """

    messages: int
    bad_packets: int
    unsigned_rejected: dict[int, int]
    signing: SigningStats | None
    refused: int = 0
    handler_faults: dict[str, int] = field(default_factory=dict)


def _axis(value: int) -> float | None:
    """A MANUAL_CONTROL axis, -1000..1000, normalized; INT16_MAX (axis unused) is NaN;
    None for any other value (a malformed message)."""
    if value == _INT16_MAX:
        return math.nan
    return value / _AXIS_LIMIT if -_AXIS_LIMIT <= value <= _AXIS_LIMIT else None


def _is_refusal(msg: Message) -> bool:
    """Whether a reply refuses the message it answers (module rule 9)."""
    if isinstance(msg, mavlink.MAVLink_mission_ack_message):
        return bool(msg.type != mavlink.MAV_MISSION_ACCEPTED)
    if isinstance(msg, mavlink.MAVLink_command_ack_message):
        return msg.result not in (mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_IN_PROGRESS)
    return isinstance(msg, mavlink.MAVLink_param_error_message)


class VehicleEndpoint:
    """The robot's MAVLink vehicle (module docstring).

    Args:
        app: the robot application.
        config: the robot's config; parameters start from its values.
        files: memory, upload area and parameter file.
        signing: sign the link; None leaves it unsigned.
        ftp: FTP server limits; None: ``config.ftp``.
        uid: the robot's unique id in AUTOPILOT_VERSION (64 bits).
        link_warning: told to every ground station that connects (rule 7); None: nothing.
        video: the camera's stream, which its component advertises (rule 10); None: no
            camera component.
        failsafe_clock: a second clock the GCS failsafe times the silence on (rule 7);
            None: the link's only.

    Raises:
        ConfigError: the parameter file is malformed, or a config value lies outside its
            parameter's range (names the file or parameter).
        InputError: the signing timestamp file cannot be read, is not one, or cannot be
            written.
        ValueError: a signing key that is not 32 bytes, or a link id outside 0..255.
    """

    def __init__(self, app: VehicleApp, config: VmnavConfig, files: VehicleFiles, *,
                 signing: SigningSetup | None = None, ftp: FtpConfig | None = None,
                 uid: int = 0, link_warning: str | None = None,
                 video: VideoStream | None = None,
                 failsafe_clock: Clock | None = None) -> None:
        link = config.mavlink
        self.address = Address(link.system_id, COMPONENT_ID)
        self.codec = make_codec(link.system_id, COMPONENT_ID)
        self._app = app
        self._files = files
        self._base_config = config
        self._table = robot_param_table(config)
        load_param_file(files.param_file, self._table)
        self.config = config_with_params(config, self._table)
        """The config in force: ``config`` with the parameters applied."""
        self._params = ParamServer(
            self._table, self.address, link,
            check=lambda name, value: param_problem(self._base_config, self._table, name, value))
        self._mission = MissionServer(self.address, link, validate=self._validate,
                                      admit=self._admit_upload)
        ftp = ftp if ftp is not None else config.ftp
        self._fs = MemoryFileSystem(files.memory_dir, files.upload_dir, ftp.upload_limit_bytes,
                                    ftp.upload_total_bytes,
                                    teaching=lambda: self._app.telemetry().teach_thumbnails)
        self._ftp = FtpServer(self._fs, ftp)
        self._intervals = MessageIntervals(default_periods_ns(link), link.min_stream_period_ns)
        builders: dict[int, Builder] = {
            _HEARTBEAT: self._heartbeat,
            mavlink.MAVLINK_MSG_ID_MISSION_CURRENT: lambda t, us: self._mission.current_message(),
            mavlink.MAVLINK_MSG_ID_SYS_STATUS: lambda t, us: sys_status_message(
                t, us, errors_comm=self.codec.bad_packets + self.shed_datagrams,
                handler_faults=self.faults.total, refused=self._refused),
            **TELEMETRY_BUILDERS,
        }
        self._streams = TelemetryStreams(builders, self._period_ns)
        self._watchdog = GcsWatchdog(link.gcs_timeout_ns)
        self._failsafe_clock = failsafe_clock
        self._progress = MissionProgress(self._mission, self._notice)
        providers = {msg_id: (lambda build=build: build(self._app.telemetry(), self._time_usec()))
                     for msg_id, build in builders.items()}
        providers[mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION] = lambda: autopilot_version_message(uid)
        self._jobs = JobCommands()
        self._commands = CommandDispatcher(self.address, {
            **vehicle_handlers(set_mode=self._set_mode, start_mission=self._start_mission,
                               set_mission_current=self._set_mission_current,
                               arm=self._arm, messages=providers, intervals=self._intervals),
            **user_handlers(app, self._fs,
                            lambda text: self._notice(mavlink.MAV_SEVERITY_WARNING, text),
                            self._jobs, lambda: self._now_ns),
        })
        self._camera: CommandDispatcher | None = None
        if video is not None:  # rule 10
            self._camera = CommandDispatcher(
                Address(link.system_id, CAMERA_COMPONENT_ID),
                camera_handlers(video, lambda: self._time_usec() // 1000))
        self._camera_outbox: list[Message] = []
        self._camera_beat_ns: int | None = None
        self._beat_state: tuple[Mode, bool] | None = None  # (mode, armed) last beaten
        self._policy: UnsignedPolicy | None = None
        self._signing_clock: SigningClock | None = None
        self._timestamp_file = signing.timestamp_file if signing is not None else None
        self._timestamps_unsaved = False
        if signing is not None:
            self._policy = configure_signing(self.codec, signing.key, signing.link_id, 0,
                                             UnsignedPolicy(UNSIGNED_ALLOWED))
            self._signing_clock = SigningClock(self.codec, signing.unix_offset_ns,
                                               SIGNING_PERIOD_NS)
            if self._timestamp_file is not None:
                kept = read_timestamp_file(self._timestamp_file)
                if kept is not None:
                    restore_timestamps(self.codec, kept)
                write_timestamp_file(self._timestamp_file, timestamps_of(self.codec))
        self._link_warning = link_warning
        self._gcs_heard = False
        self._outbox: list[Message] = []
        self.shed_datagrams = 0
        """Datagrams the transport dropped unparsed under a flood (its owner counts them)."""
        self._messages = 0
        self._refused = 0
        self.faults = HandlerFaults(logger, "vehicle")
        """Exceptions of the handlers (rule 9); the UDP adapter records its own here too."""
        self._boot_ns: int | None = None
        self._now_ns = 0
        self._notice_id = 0
        app.params_changed(self.config)

    # -- the I/O surface ----------------------------------------------------------------

    def receive(self, data: bytes, now_ns: int, datagram: bool = False,
                verified: list[bytes] | None = None) -> int:
        """Handle every packet in ``data``: a chunk of a byte stream, or with ``datagram``
        one whole datagram (a packet it leaves unfinished is corrupt, not continued by
        the next one: :meth:`~shared.mavlink.dialect.MavlinkCodec.parse`).

        Args:
            data: the bytes received.
            now_ns: the time, ns.
            datagram: ``data`` is one whole datagram.
            verified: when given, the bytes of each verified packet in ``data``
                (:meth:`~shared.mavlink.dialect.MavlinkCodec.is_verified`) are appended,
                whole: what a stream transport logs (its chunks split packets).

        Returns:
            How many messages were accepted (0 when all were corrupt or unsigned).
        """
        self._tick(now_ns)
        self._keep_signing(now_ns)
        messages = self.codec.parse(data, datagram)
        if verified is not None:
            verified += [bytes(m.get_msgbuf()) for m in messages if self.codec.is_verified(m)]
        for msg in messages:
            try:
                replies = self._handle(msg, now_ns)
                replies += self._drain_events()
                camera = [] if self._camera is None else self._camera.handle_message(msg)
            except Exception as e:  # a bug; one packet must not end the link (rule 9)
                self.faults.record(msg.get_type(), e)
                continue
            self._refused += sum(map(_is_refusal, replies + camera))
            self._outbox += replies
            self._camera_outbox += camera
        self._messages += len(messages)
        return len(messages)

    def poll(self, now_ns: int) -> list[bytes]:
        """Everything due at ``now_ns``: replies, timer retries, heartbeat, telemetry,
        progress and failsafe notices; one packed MAVLink packet per element."""
        self._tick(now_ns)
        self._keep_signing(now_ns)
        out, self._outbox = self._outbox, []
        t = self._app.telemetry()
        if self._beat_state not in (None, (t.mode, t.armed)):
            out.append(self._heartbeat(t, self._time_usec()))
        self._beat_state = (t.mode, t.armed)
        out += self._progress.update(t, self._time_usec())
        while (notice := self._app.next_notice()) is not None:
            out += self._notice(_SEVERITIES.get(notice[0], mavlink.MAV_SEVERITY_INFO), notice[1])
        while (outcome := self._app.next_job_outcome()) is not None:
            out += self._jobs.finish(outcome)
        out += self._jobs.progress(now_ns)
        out += self._check_gcs(t, now_ns)
        out += self._streams.due(t, now_ns, self._time_usec())
        for core in (self._mission, self._params):
            timer = core.get_timer()
            if timer is not None and now_ns >= timer:
                out += core.handle_timer(now_ns)
        out += self._drain_events()
        camera, self._camera_outbox = self._camera_outbox, []
        if self._camera is not None and (self._camera_beat_ns is None
                                         or now_ns >= self._camera_beat_ns):
            camera.append(camera_heartbeat())  # rule 10
            self._camera_beat_ns = now_ns + self.config.mavlink.heartbeat_period_ns
        return ([self.codec.pack(msg) for msg in out]
                + [self.codec.pack_as(msg, CAMERA_COMPONENT_ID) for msg in camera])

    def get_timer(self) -> int | None:
        """When :meth:`poll` next has something to send, ns (0: at once)."""
        if self._outbox or self._camera_outbox:
            return self._now_ns
        timers = [self._streams.get_timer(), self._mission.get_timer(),
                  self._params.get_timer(), self._jobs.get_timer()]
        if self._failsafe_clock is None:  # on two clocks, every poll checks it instead:
            timers.append(self._watchdog.get_timer())  # its link deadline may pass unlost
        if self._camera is not None:
            timers.append(self._camera_beat_ns or 0)
        if self._signing_clock is not None:
            timers.append(self._signing_clock.get_timer() or 0)
        return min((t for t in timers if t is not None), default=None)

    def stats(self) -> LinkStats:
        """Counters of what was received."""
        return LinkStats(
            self._messages, self.codec.bad_packets,
            dict(self._policy.rejected) if self._policy is not None else {},
            signing_stats(self.codec) if self._policy is not None else None,
            self._refused, self.faults.counts())

    def close(self) -> None:
        """Discard FTP uploads in progress (nothing half-written is kept); keep the signing
        timestamps (rule 8)."""
        self._ftp.close()
        self._save_timestamps()

    # -- signing ------------------------------------------------------------------------

    def _keep_signing(self, now_ns: int) -> None:
        """When due, raise the signing timestamp to the wall clock and keep it (rule 8)."""
        clock = self._signing_clock
        if clock is not None and now_ns >= (clock.get_timer() or 0):
            clock.handle_timer(now_ns)
            self._save_timestamps()

    def _save_timestamps(self) -> None:
        if self._timestamp_file is None:
            return
        try:
            write_timestamp_file(self._timestamp_file, timestamps_of(self.codec))
        except InputError as e:
            if not self._timestamps_unsaved:
                self._outbox += self._notice(mavlink.MAV_SEVERITY_ERROR,
                                             f"signing timestamps not saved: {e}")
            self._timestamps_unsaved = True

    # -- input --------------------------------------------------------------------------

    def _handle(self, msg: Any, now_ns: int) -> list[Message]:
        if isinstance(msg, mavlink.MAVLink_heartbeat_message):
            return self._on_heartbeat(msg, now_ns)
        if isinstance(msg, mavlink.MAVLink_file_transfer_protocol_message):
            if msg.target_network != 0 or not is_for(msg, self.address):
                return []
            peer = (msg.get_srcSystem(), msg.get_srcComponent())
            return [mavlink.MAVLink_file_transfer_protocol_message(0, *peer, payload)
                    for payload in self._ftp.handle(msg.payload, now_ns, peer)]
        if isinstance(msg, mavlink.MAVLink_manual_control_message):
            if msg.target in (0, self.address.system_id):
                x, y, z, r = axes = (_axis(msg.x), _axis(msg.y), _axis(msg.z), _axis(msg.r))
                if x is None or y is None or z is None or r is None:
                    logger.debug("vehicle: MANUAL_CONTROL axes %s out of range: dropped", axes)
                    self._refused += 1
                else:
                    self._app.manual_control(x, y, z, r, msg.buttons, now_ns)
            return []
        if isinstance(msg, mavlink.MAVLink_set_mode_message):
            if is_for(msg, self.address):
                mode = mode_from_set_mode(msg.base_mode, msg.custom_mode)
                if mode is None:
                    self._refused += 1
                else:
                    self._set_mode(mode)
            return []
        if isinstance(msg, mavlink.MAVLink_timesync_message):
            return [mavlink.MAVLink_timesync_message(now_ns, msg.ts1)] if msg.tc1 == 0 else []
        return (self._commands.handle_message(msg) + self._mission.handle_message(msg, now_ns)
                + self._params.handle_message(msg, now_ns))

    def _on_heartbeat(self, msg: Any, now_ns: int) -> list[Message]:
        if msg.type != mavlink.MAV_TYPE_GCS:
            return []
        first, self._gcs_heard = not self._gcs_heard, True
        out: list[Message] = []
        regained = self._watchdog.heartbeat(*self._failsafe_ns(now_ns))
        if regained:
            self._app.gcs_regained()
            out += self._notice(mavlink.MAV_SEVERITY_INFO, "GCS heartbeat regained")
        if self._link_warning is not None and (first or regained):
            out += self._notice(mavlink.MAV_SEVERITY_WARNING, self._link_warning)
        return out

    def _drain_events(self) -> list[Message]:
        """Persist and apply parameter changes; log mission events."""
        out: list[Message] = []
        while (event := self._params.next_event()) is not None:
            logger.info("vehicle: %s", event)
            if isinstance(event, ParamChanged):
                out += self._apply_params()
        while (mission_event := self._mission.next_event()) is not None:
            logger.info("vehicle: %s", mission_event)
        return out

    def _apply_params(self) -> list[Message]:
        out: list[Message] = []
        try:
            save_param_file(self._files.param_file, self._table)
        except InputError as e:
            out = self._notice(mavlink.MAV_SEVERITY_ERROR, f"params not saved: {e}")
        self.config = config_with_params(self._base_config, self._table)
        self._app.params_changed(self.config)
        return out

    # -- command callbacks --------------------------------------------------------------

    def _set_mode(self, mode: Mode) -> int:
        if mode is Mode.AUTO:
            return self._start_mission(self._mission.current_seq, None)
        return self._result(self._app.set_mode(mode))

    def _start_mission(self, first: int, last: int | None) -> int:
        items = self._mission.items
        last = len(items) - 1 if last is None else last
        if not 0 <= first <= last < len(items):
            self._outbox += self._notice(mavlink.MAV_SEVERITY_WARNING,
                                         f"mission: cannot run items {first}..{last} "
                                         f"of {len(items)}")
            return mavlink.MAV_RESULT_DENIED
        goals = _goals(items)[first:last + 1]
        if not self._app.start_mission(goals, first):
            return mavlink.MAV_RESULT_DENIED
        self._mission.set_current(first)
        return mavlink.MAV_RESULT_ACCEPTED

    def _set_mission_current(self, seq: int) -> int:
        if not self._mission.set_current(seq):
            return mavlink.MAV_RESULT_DENIED
        self._outbox.append(self._mission.current_message())
        return mavlink.MAV_RESULT_ACCEPTED

    def _arm(self, armed: bool, force: bool) -> int:
        return self._result(self._app.arm(armed, force))

    @staticmethod
    def _result(ok: bool) -> int:
        return mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_DENIED

    def _admit_upload(self) -> MissionRefusal | None:
        """The mission server's admission hook: no upload while the mission runs (rule 4)."""
        if self._app.telemetry().mission_running:
            return MissionRefusal(mavlink.MAV_MISSION_DENIED,
                                  "the mission is running; switch to HOLD first")
        return None

    def _validate(self, items: tuple[MissionItem, ...]) -> MissionRefusal | None:
        """The mission server's validation hook (module rule 4): asked again at the end,
        since the mission may have started during the upload."""
        refusal = self._admit_upload()
        if refusal is not None or not items:
            return refusal
        goals = goals_from_items(items)
        if isinstance(goals, MissionRefusal):
            return goals
        return self._app.validate_goals(goals)

    # -- output -------------------------------------------------------------------------

    def _check_gcs(self, t: VehicleTelemetry, now_ns: int) -> list[Message]:
        silence_ns = self._watchdog.check(*self._failsafe_ns(now_ns))
        if silence_ns is None:
            return []
        action = gcs_lost_action(t.mode, self.config.mavlink.gcs_lost_action)
        self._app.gcs_lost(action)
        return self._notice(mavlink.MAV_SEVERITY_CRITICAL,  # one STATUSTEXT: <= 50 characters
                            f"GCS heartbeat lost for {silence_ns / 1e9:.1f} s in "
                            f"{t.mode.name}: {action}")

    def _failsafe_ns(self, now_ns: int) -> tuple[int, ...]:
        """The failsafe's times (rule 7): the link's, then ``failsafe_clock``'s, ns."""
        if self._failsafe_clock is None:
            return (now_ns,)
        return now_ns, self._failsafe_clock.now_ns()

    def _heartbeat(self, t: VehicleTelemetry, time_usec: int) -> Message:
        return heartbeat_message(t.mode, t.armed, system_status(t, self._watchdog.lost))

    def _period_ns(self, msg_id: int) -> int | None:
        if msg_id == _HEARTBEAT:
            return self.config.mavlink.heartbeat_period_ns
        return self._intervals.interval_ns(msg_id)

    def _notice(self, severity: int, text: str) -> list[Message]:
        logger.info("vehicle: %s", text)
        self._notice_id = self._notice_id % 0xFFFF + 1
        return statustext_messages(severity, text, self._notice_id)

    def _tick(self, now_ns: int) -> None:
        if self._boot_ns is None:
            self._boot_ns = now_ns
        self._now_ns = now_ns

    def _time_usec(self) -> int:
        """Time since the endpoint first ran, us (MAVLink's "time since boot")."""
        return (self._now_ns - (self._boot_ns or 0)) // 1000


def _goals(items: tuple[MissionItem, ...]) -> tuple[Goal, ...]:
    """The goals of a mission the server accepted (so every item decodes)."""
    goals = goals_from_items(items)
    assert not isinstance(goals, MissionRefusal), goals
    return goals
