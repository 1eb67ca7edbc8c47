"""GroundStation: the operator's end of the MAVLink link, with a blocking API.

Theory of operation
-------------------

The station owns a :class:`~shared.udp_link.UdpLink` (``udpin:HOST:14550``, where
QGroundControl listens, or ``udpout:HOST:PORT``; ``vmnav ground`` keeps an unsigned one
on loopback: ``shared.link_security``) or a :class:`~shared.stream_port.StreamPort`
(``serial:DEVICE[:BAUD]``, a telemetry radio; ``tcp:HOST:PORT``; ``tcpin:HOST:PORT``,
where a robot calls in; rule 9), one
codec, the :class:`~ground.fleet.Fleet` of vehicles it hears, and the sans-I/O client cores
(missions, parameters, FTP, commands) aimed at the one vehicle it talks to. Each
blocking call starts an operation on a core and runs :meth:`GroundStation.service`
until the core reports its outcome; the cores' own timeouts and retries bound it.

Rules:

1. Identity: system 255, component 190 (MAV_COMP_ID_MISSIONPLANNER), a GCS
   HEARTBEAT every second from the first service on. A listening link sends to every
   vehicle it heard (each from its own UDP address); before any, to the last sender.
2. :meth:`~GroundStation.wait_vehicle` picks the vehicle: the system asked for, or the
   first one heard. While it waits each beat also broadcasts a REQUEST_MESSAGE for
   HEARTBEAT, so a vehicle that answers only known peers replies at once rather than
   at its next beat.
3. Waiting: the station waits for a datagram with ``select`` up to the next
   deadline of the injected clock (heartbeat, client timers, the caller's limit),
   then sleeps on the clock to that deadline; with the wall clock the second wait is
   nil. All deadlines are clock ns.
4. Failures of the vehicle (no answer, a refusal) raise :class:`GroundError` with one
   line naming the request; a refusal carries the vehicle's STATUSTEXT reason when
   one follows within :data:`REASON_WAIT_NS`. A goal run that ends short is a result
   (:meth:`~GroundStation.wait_mission_done` returns False), not an error.
5. Signing (a key given): everything sent is signed, unsigned or badly signed
   packets are dropped by the codec, and the signing timestamp follows the wall
   clock (``SigningClock``).
6. Taps: every verified packet received (a message of our dialect, validly signed on a
   signed link: what strangers' garbage and unknown ids are not) and every packet sent
   (once per datagram) goes to each of :attr:`~GroundStation.packet_taps`, in wire
   order, with its bytes, its message and the clock's reading at that moment (e.g.
   ``ground.ground_log``).
7. Floods: each service drains the socket
   (:meth:`~shared.udp_link.UdpLink.drain`): every datagram from a vehicle heard
   (its UDP address) is handled, of anyone else's at most :data:`STRANGER_BUDGET`,
   the rest dropped unparsed (counted in :attr:`GroundStation.shed`); a listening
   link's peer becomes the sender of the last datagram handled.
8. Each datagram received is parsed on its own
   (:meth:`~shared.mavlink.dialect.MavlinkCodec.parse` with ``datagram``): a packet it
   leaves unfinished is corrupt, counted in ``codec.bad_packets`` and dropped, so garbage
   that reads as the start of a long packet cannot swallow the packets of the datagrams
   after it.
9. Streams: a serial device or a ``tcp`` connection is opened by :meth:`open` (a
   missing device, an unknown host or a refused or unanswered connect: one line at
   once); a ``tcpin`` listener is bound there and takes the first robot that calls
   (while the station waits, e.g. :meth:`wait_vehicle`). What arrives is parsed as a
   byte stream, from the one peer; a stream that ends (the robot's connection closed,
   the radio unplugged) raises :class:`~shared.byte_link.LinkClosedError` in one line
   from the call that was waiting. Floods and peers (rule 7) are UDP matters.
"""

from __future__ import annotations

import select
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ground.fleet import Fleet, VehicleState
from ground.mission_watch import MissionWatch
from shared.clock import NS_PER_S, Clock
from shared.config import FtpConfig, MavlinkConfig
from shared.errors import IllegalEventError, InputError, VmnavError
from shared.link_address import Scheme, parse_link_address
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.commands.gcs import CommandClient, CommandDone, result_name
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP, params_from_name
from shared.mavlink.commands.user import NAMES as USER_COMMANDS
from shared.mavlink.commands.vehicle import FORCE_ARM_MAGIC
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.ftp.gcs import Downloaded, FtpClient, FtpFailed, Listed, Uploaded
from shared.mavlink.ftp.payload import DirEntry
from shared.mavlink.mission.gcs import MissionClient, OperationRefused, UploadDone
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.mavlink.params.gcs import (
    ParamClient,
    ParamOperationFailed,
    ParamReceived,
    ParamSetDone,
    ParamsFetched,
)
from shared.mavlink.signing import SigningClock, configure_signing, timestamp_from_unix_ns
from shared.stream_port import StreamPort
from shared.udp_link import Peer, UdpLink

#: This station: system 255, MAV_COMP_ID_MISSIONPLANNER.
GCS_ADDRESS = Address(255, 190)
#: Period of the station's HEARTBEAT, ns.
HEARTBEAT_PERIOD_NS = NS_PER_S
#: How long to wait for the STATUSTEXT that explains a refusal, ns.
REASON_WAIT_NS = 300_000_000
#: Backstop for an operation whose core never ends it (cores end every one), ns.
OPERATION_LIMIT_NS = 600 * NS_PER_S
#: How long :meth:`GroundStation.arm` waits for a HEARTBEAT saying armed (heartbeats come
#: at 1 Hz), ns.
ARM_WAIT_NS = 5 * NS_PER_S
#: MANUAL_CONTROL value of an axis not sent (common.xml).
UNUSED_AXIS = 0x7FFF
#: Signing link id of the station (the vehicle signs as link 0).
SIGNING_LINK_ID = 1
#: Datagrams from senders other than the vehicles heard handled per service at most (rule 7).
STRANGER_BUDGET = 64

#: (vehicle, message) -> None, called for every message from a known vehicle.
Listener = Callable[[VehicleState, Any], None]
#: (direction ``"in"``/``"out"``, packet bytes, its message, clock ns) -> None (rule 6).
PacketTap = Callable[[str, bytes, Message, int], None]


class GroundError(VmnavError):
    """The vehicle did not answer a request, or refused it (one line; in the tree under
    :class:`~shared.errors.VmnavError`)."""


@dataclass(frozen=True, slots=True)
class PhotoGoal:
    """A photo the robot found in its memory and now drives to.

    Attributes:
        photo_id: the id it was uploaded under (``/upload/<id>.<ext>``).
        keyframe_id: the key image it was found at: the goal.
        said: the robot's line about it (the key image's matches and verified inliers);
            "" if that STATUSTEXT was lost.
    """

    photo_id: int
    keyframe_id: int
    said: str


@dataclass(frozen=True, slots=True)
class StoredPath:
    """A taught path the robot stored.

    Attributes:
        path_id: its id in the memory.
        said: the robot's line about it (key images, junctions); "" if that STATUSTEXT
            was lost.
    """

    path_id: int
    said: str


def _command_name(command: int) -> str:
    if command in USER_COMMANDS:
        return USER_COMMANDS[command]
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"command {command}"


class GroundStation:
    """A MAVLink ground station on one link (module rules).

    Args:
        link: the socket or stream port; the station owns it.
        clock: time for deadlines and waits.
        system_id: the vehicle to talk to; None for the first one heard.
        key: a 32-byte signing key; None for an unsigned link.
        unix_offset_ns: Unix time minus ``clock``'s reading, ns (signing timestamps).
        config: mission and parameter timeouts and retries.
        ftp: FTP timeouts, retries and packet sizes.

    Raises:
        ValueError: a signing key that is not 32 bytes.
    """

    def __init__(self, link: UdpLink | StreamPort, clock: Clock, *,
                 system_id: int | None = None,
                 key: bytes | None = None, unix_offset_ns: int = 0,
                 config: MavlinkConfig | None = None, ftp: FtpConfig | None = None) -> None:
        self.link = link
        self.address = GCS_ADDRESS
        self.codec = make_codec(GCS_ADDRESS.system_id, GCS_ADDRESS.component_id)
        self.fleet = Fleet()
        self.system_id = system_id
        self.listeners: list[Listener] = []
        """Called with every message from a known vehicle (e.g. to print telemetry)."""
        self.packet_taps: list[PacketTap] = []
        """Called with every packet received or sent (rule 6)."""
        self.clock = clock
        """The station's time: deadlines and waits."""
        self._config = config if config is not None else MavlinkConfig()
        self._ftp_config = ftp
        self._signing: SigningClock | None = None
        if key is not None:
            configure_signing(self.codec, key, SIGNING_LINK_ID,
                              timestamp_from_unix_ns(clock.now_ns() + unix_offset_ns))
            self._signing = SigningClock(self.codec, unix_offset_ns)
        self.vehicle: VehicleState | None = None
        """The vehicle the clients talk to, once :meth:`wait_vehicle` found it."""
        self._mission: MissionClient | None = None
        self._params: ParamClient | None = None
        self._commands: CommandClient | None = None
        self._component_commands: CommandClient | None = None  # command_to's, while it runs
        self._ftp = FtpClient(ftp)
        self._watch: MissionWatch | None = None
        self._mission_count = 0
        self._next_beat_ns: int | None = None
        self._discovering = False
        self.shed = 0
        """Datagrams from strangers dropped unparsed under a flood (rule 7)."""

    @classmethod
    def open(cls, url: str, clock: Clock, **options: Any) -> GroundStation:
        """A station on a new link for ``url`` (``shared.link_address``: ``udpin:...``,
        ``udpout:...``, ``tcp:...``, ``tcpin:...``, ``serial:...``, ``pty:...``).

        Raises:
            InputError: ``url`` is not a link address.
            TransportError: a port in use, a missing device, an unknown host, a refused
                or unanswered connect (rule 9).
        """
        address = parse_link_address(url, "--connect")
        if not address.stream:
            return cls(UdpLink.open(url), clock, **options)
        port = StreamPort.open(address)
        try:
            if address.scheme is not Scheme.TCPIN:
                port.connect()
        except BaseException:
            port.close()
            raise
        return cls(port, clock, **options)

    def close(self) -> None:
        """Close the link; idempotent."""
        self.link.close()

    def __enter__(self) -> GroundStation:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the loop -----------------------------------------------------------------------

    def service(self) -> None:
        """One round at the clock's now: the waiting datagrams in (rule 7, each parsed on
        its own, rule 8), everything due out."""
        now_ns = self.clock.now_ns()
        stream = isinstance(self.link, StreamPort)
        for data, sender in self._stream_in() if stream else self._datagrams_in():
            for msg in self.codec.parse(data, datagram=not stream):
                if self.codec.is_verified(msg):
                    self._tap("in", bytes(msg.get_msgbuf()), msg)
                self._handle(msg, sender, now_ns)
        if self._signing is not None and now_ns >= (self._signing.get_timer() or 0):
            self._signing.handle_timer(now_ns)
        if self._next_beat_ns is None or now_ns >= self._next_beat_ns:
            self._beat()
            self._next_beat_ns = now_ns + HEARTBEAT_PERIOD_NS
        for core in (self._mission, self._params, self._commands, self._component_commands):
            timer = core.get_timer() if core is not None else None
            if core is not None and timer is not None and now_ns >= timer:
                self._send(core.handle_timer(now_ns))
        timer = self._ftp.get_timer()
        if timer is not None and now_ns >= timer:
            self._ftp.handle_timer(now_ns)
        self._send_ftp()

    def _datagrams_in(self) -> list[tuple[bytes, Peer]]:
        """The datagrams waiting on the UDP link (rule 7)."""
        assert isinstance(self.link, UdpLink)
        trusted = {v.peer for v in self.fleet.vehicles.values() if v.peer is not None}
        drained = self.link.drain(trusted, STRANGER_BUDGET)
        self.shed += drained.shed
        received = drained.trusted + drained.others
        if received and self.link.listening:
            self.link.peer = received[-1][1]
        return received

    def _stream_in(self) -> list[tuple[bytes, None]]:
        """What arrived on the stream, from its one peer (rule 9).

        Raises:
            LinkClosedError: the stream ended.
        """
        assert isinstance(self.link, StreamPort)
        if not self.link.connect():  # a tcpin listener with no robot yet
            return []
        data = self.link.read()
        return [(data, None)] if data else []

    def run_until(self, done: Callable[[], bool], timeout_ns: int) -> bool:
        """Service the link until ``done()`` or ``timeout_ns`` passed (rule 3).

        Returns:
            Whether ``done()`` became true.
        """
        limit_ns = self.clock.now_ns() + timeout_ns
        while True:
            self.service()
            if done():
                return True
            now_ns = self.clock.now_ns()
            if now_ns >= limit_ns:
                return False
            deadline_ns = min(limit_ns, self._next_deadline_ns())
            ready = select.select([self.link.fileno()], [], [],
                                  max(0, deadline_ns - now_ns) / NS_PER_S)[0]
            if not ready:
                self.clock.sleep_until_ns(deadline_ns)

    def _next_deadline_ns(self) -> int:
        timers = [self._next_beat_ns, self._ftp.get_timer()]
        timers += [core.get_timer() for core in (self._mission, self._params, self._commands,
                                                 self._component_commands)
                   if core is not None]
        if self._signing is not None:
            timers.append(self._signing.get_timer())
        return min(t for t in timers if t is not None)

    def _handle(self, msg: Any, sender: Peer | None, now_ns: int) -> None:
        vehicle = self.fleet.handle(msg, sender, now_ns)
        if vehicle is None:
            return
        for listener in self.listeners:
            listener(vehicle, msg)
        other = self._component_commands
        if other is not None and source_of(msg) == other.vehicle:
            self._send(other.handle_message(msg, now_ns))
        if self.vehicle is None or source_of(msg) != self.vehicle.address:
            return
        for core in (self._mission, self._params, self._commands):
            if core is not None:
                self._send(core.handle_message(msg, now_ns))
        if (isinstance(msg, mavlink.MAVLink_file_transfer_protocol_message)
                and msg.target_network == 0 and is_for(msg, self.address)):
            self._ftp.receive_payload(msg.payload, now_ns)
        if self._watch is not None:
            self._watch.handle_message(msg)

    def _beat(self) -> None:
        messages: list[Message] = [mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
            mavlink.MAV_STATE_ACTIVE, 3)]
        if self._discovering:
            messages.append(mavlink.MAVLink_command_long_message(
                0, 0, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                mavlink.MAVLINK_MSG_ID_HEARTBEAT, 0, 0, 0, 0, 0, 0))
        packets = [(msg, self.codec.pack(msg)) for msg in messages]
        if isinstance(self.link, StreamPort):
            for msg, packet in packets:
                self._transmit(msg, packet)
            return
        peers = {v.peer for v in self.fleet.vehicles.values() if v.peer is not None}
        if not self.link.listening or not peers:
            peers = {self.link.peer} if self.link.peer is not None else set()
        for peer in peers:
            self.link.peer = peer
            for msg, packet in packets:
                self._transmit(msg, packet)

    def _send(self, messages: Sequence[Message]) -> None:
        """Send ``messages`` to the vehicle talked to (its own address when listening)."""
        if not messages:
            return
        if (isinstance(self.link, UdpLink) and self.link.listening and self.vehicle is not None
                and self.vehicle.peer is not None):
            self.link.peer = self.vehicle.peer
        for msg in messages:
            self._transmit(msg, self.codec.pack(msg))

    def _transmit(self, msg: Message, packet: bytes) -> None:
        """Send one packet to the link's peer and show it to the taps (rule 6)."""
        if isinstance(self.link, StreamPort):
            if not self.link.write(packet):
                return  # a tcpin listener with no robot yet
        else:
            self.link.send(packet)
        self._tap("out", packet, msg)

    def _tap(self, direction: str, packet: bytes, msg: Message) -> None:
        if self.packet_taps:
            now_ns = self.clock.now_ns()
            for tap in self.packet_taps:
                tap(direction, packet, msg, now_ns)

    def _send_ftp(self) -> None:
        payloads = self._ftp.payloads_to_send()
        if payloads and self.vehicle is not None:
            target = self.vehicle.address
            self._send([mavlink.MAVLink_file_transfer_protocol_message(
                0, target.system_id, target.component_id, payload) for payload in payloads])

    # -- vehicles -----------------------------------------------------------------------

    def wait_vehicle(self, timeout_s: float) -> VehicleState:
        """Wait for the vehicle's HEARTBEAT and aim the clients at it (rule 2).

        Args:
            timeout_s: how long to wait, s.

        Raises:
            GroundError: no such vehicle within ``timeout_s``.
        """
        def found() -> VehicleState | None:
            if self.system_id is not None:
                return self.fleet.vehicles.get(self.system_id)
            return next(iter(self.fleet.vehicles.values()), None)

        self._discovering, self._next_beat_ns = True, None
        try:
            self.run_until(lambda: found() is not None, round(timeout_s * NS_PER_S))
        finally:
            self._discovering = False
        vehicle = found()
        if vehicle is None:
            who = "a vehicle" if self.system_id is None else f"vehicle {self.system_id}"
            heard = sorted(self.fleet.vehicles)
            also = f" (heard systems {', '.join(map(str, heard))})" if heard else ""
            raise GroundError(f"{self.link.url}: no HEARTBEAT from {who} "
                              f"within {timeout_s:.1f} s{also}")
        self.vehicle = vehicle
        self._mission = MissionClient(self.address, vehicle.address, self._config)
        self._params = ParamClient(self.address, vehicle.address, self._config)
        self._commands = CommandClient(self.address, vehicle.address)
        return vehicle

    def _target(self, request: str) -> VehicleState:
        if self.vehicle is None:
            raise IllegalEventError("ground station", "NO_VEHICLE", request)
        return self.vehicle

    def _reason(self, notices_before: int) -> str:
        """The vehicle's first STATUSTEXT after ``notices_before`` (rule 4), as `` (text)``."""
        vehicle = self._target("reason")
        self.run_until(lambda: len(vehicle.notices) > notices_before, REASON_WAIT_NS)
        later = vehicle.notices[notices_before:]
        return f" ({later[0]})" if later else ""

    def _finish(self, core: Any) -> Any:
        """Run until ``core`` reports its outcome; return it."""
        events: list[Any] = []

        def done() -> bool:
            event = core.next_event()
            if event is not None:
                events.append(event)
            return bool(events)

        if not self.run_until(done, OPERATION_LIMIT_NS):
            raise GroundError(f"no outcome after {OPERATION_LIMIT_NS // NS_PER_S} s")
        return events[0]

    # -- commands -----------------------------------------------------------------------

    def command_long(self, command: int, *params: float) -> int:
        """Send COMMAND_LONG ``command`` (params 1-7, unset ones NaN) and wait for its final
        ACK (through any ``MAV_RESULT_IN_PROGRESS``).

        Returns:
            The ``MAV_RESULT``.

        Raises:
            GroundError: no ACK after the resends.
        """
        return self._command_done(command, params).result

    def _command_done(self, command: int, params: tuple[float, ...]) -> CommandDone:
        self._target("command_long")
        assert self._commands is not None
        self._send(self._commands.send(command, tuple(params), self.clock.now_ns()))
        outcome = self._finish(self._commands)
        if not isinstance(outcome, CommandDone):
            raise GroundError(f"no COMMAND_ACK to {_command_name(command)} "
                              f"after {outcome.sends} tries")
        return outcome

    def command_to(self, component_id: int, command: int, *params: float) -> CommandDone:
        """Send COMMAND_LONG ``command`` to another component of the vehicle (its camera)
        and wait for that component's final ACK.

        Raises:
            GroundError: no ACK after the resends.
        """
        vehicle = self._target("command_to")
        client = CommandClient(self.address, Address(vehicle.system_id, component_id))
        self._component_commands = client
        try:
            self._send(client.send(command, tuple(params), self.clock.now_ns()))
            outcome = self._finish(client)
        finally:
            self._component_commands = None
        if not isinstance(outcome, CommandDone):
            raise GroundError(f"no COMMAND_ACK to {_command_name(command)} from component "
                              f"{component_id} of vehicle {vehicle.system_id} after "
                              f"{outcome.sends} tries")
        return outcome

    def command(self, command: int, *params: float) -> CommandDone:
        """:meth:`command_long`, and anything but ACCEPTED is an error.

        Returns:
            The final ACK's outcome (its ``result_param2`` means what the command says).

        Raises:
            GroundError: no ACK, or a result other than ACCEPTED (with the reason).
        """
        vehicle = self._target("command")
        before = len(vehicle.notices)
        done = self._command_done(command, params)
        if not done.accepted:
            raise GroundError(f"vehicle {vehicle.system_id} answered {_command_name(command)} "
                              f"with {result_name(done.result)}{self._reason(before)}")
        return done

    def emergency_stop(self) -> None:
        """Stop the vehicle now: a forced disarm (COMPONENT_ARM_DISARM, param2 21196), the
        emergency stop of QGroundControl and ArduRover; the robot holds until re-armed.

        Raises:
            GroundError: refused or unanswered.
        """
        self.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, FORCE_ARM_MAGIC)

    def arm(self) -> None:
        """Arm the vehicle (COMPONENT_ARM_DISARM 1), which ends an emergency stop's hold, and
        wait until its HEARTBEAT says armed (the robot applies the request on its next
        frame; a mission started before that is refused).

        Raises:
            GroundError: refused, unanswered, or not armed within :data:`ARM_WAIT_NS`.
        """
        vehicle = self._target("arm")
        self.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
        if not self.run_until(lambda: vehicle.armed, ARM_WAIT_NS):
            raise GroundError(f"vehicle {vehicle.system_id} accepted arming but did not "
                              f"report armed within {ARM_WAIT_NS // NS_PER_S} s")

    def set_mode(self, mode: Mode) -> None:
        """Switch the vehicle to ``mode`` (DO_SET_MODE, ArduPilot encoding).

        Raises:
            GroundError: refused or unanswered.
        """
        self.command(mavlink.MAV_CMD_DO_SET_MODE,
                     mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, int(mode))

    def request_message(self, msg_id: int, timeout_s: float = 1.0) -> Any | None:
        """Ask for one message now (REQUEST_MESSAGE); None if refused or not received.

        Args:
            msg_id: the MAVLink message id.
            timeout_s: how long to wait for the message after the ACK, s.
        """
        vehicle = self._target("request_message")
        name = mavlink.mavlink_map[msg_id].msgname
        old = vehicle.telemetry.get(name)
        if self.command_long(mavlink.MAV_CMD_REQUEST_MESSAGE, msg_id) != \
                mavlink.MAV_RESULT_ACCEPTED:
            return None
        self.run_until(lambda: vehicle.telemetry.get(name) is not old,
                       round(timeout_s * NS_PER_S))
        new = vehicle.telemetry.get(name)
        return new if new is not old else None

    # -- missions -----------------------------------------------------------------------

    def upload_goals(self, goals: Sequence[Goal]) -> None:
        """Replace the vehicle's mission with one goal item per goal.

        Raises:
            GroundError: the vehicle refused the mission (its MAV_MISSION_RESULT and
                reason; it keeps the mission it had) or stopped answering.
        """
        vehicle = self._target("upload_goals")
        assert self._mission is not None
        before = len(vehicle.notices)
        items = tuple(goal.to_item() for goal in goals)
        self._send(self._mission.upload(items, self.clock.now_ns()))
        outcome = self._finish(self._mission)
        if isinstance(outcome, OperationRefused):
            raise GroundError(f"vehicle {vehicle.system_id} refused the mission: "
                              f"{outcome.result_name}{self._reason(before)}")
        if not isinstance(outcome, UploadDone):
            raise GroundError(f"mission upload to vehicle {vehicle.system_id}: {outcome.reason}")
        self._mission_count = len(items)

    def start_mission(self) -> None:
        """Run the uploaded mission from its first item (MISSION_START) and start
        following it for :meth:`wait_mission_done`.

        Raises:
            GroundError: refused or unanswered.
        """
        self._watch = MissionWatch(self._mission_count - 1 if self._mission_count else None)
        self.command(mavlink.MAV_CMD_MISSION_START, 0)

    def goto_photo(self, data: bytes, suffix: str) -> PhotoGoal:
        """Upload a photo of the goal as ``/upload/<id><suffix>`` (a new id), send the
        go-to-photo command and wait while the robot looks the photo up in its memory
        (a long-running command: ``robot.vehicle.user_commands``); follow the run for
        :meth:`wait_mission_done`.

        Args:
            data: the encoded image (JPEG, PNG...).
            suffix: its file extension with the dot, e.g. ``".jpg"``.

        Returns:
            The photo's id, the key image it was found at (the goal) and the robot's words.

        Raises:
            GroundError: the upload failed, the command was refused, or the photo was not
                found in the memory (with the robot's reason).
        """
        vehicle = self._target("goto_photo")
        taken = [e.name.partition(".")[0] for e in self.ftp_list("/upload")]
        photo_id = 1 + max((int(stem) for stem in taken if stem.isdigit()), default=0)
        self.ftp_put(f"/upload/{photo_id}{suffix}", data)
        self._watch = MissionWatch(None)
        before = len(vehicle.notices)
        done = self.command(GOTO_PHOTO, photo_id)
        said = [n for n in vehicle.notices[before:] if n.startswith(f"photo {photo_id}{suffix}:")]
        return PhotoGoal(photo_id, done.result_param2, said[0] if said else "")

    def teach_start(self, name: str) -> None:
        """Start recording a visual path called ``name`` ("" lets the robot name it).

        Raises:
            InputError: ``name`` is not up to 21 printable ASCII characters.
            GroundError: refused (already teaching...) or unanswered.
        """
        try:
            params = params_from_name(name)
        except ValueError as e:
            raise InputError("NAME", str(e)) from None
        self.command(TEACH_START, *params)

    def teach_stop(self) -> StoredPath:
        """Stop recording and wait while the robot joins the path to its memory and writes
        it (a long-running command: ``robot.vehicle.user_commands``).

        Returns:
            The id of the path stored and the robot's words about it.

        Raises:
            GroundError: refused (not teaching), unanswered, or nothing stored (too short a
                drive, the memory not writable: with the robot's reason).
        """
        vehicle = self._target("teach_stop")
        before = len(vehicle.notices)
        done = self.command(TEACH_STOP)
        said = [n for n in vehicle.notices[before:] if n.startswith(f"path {done.result_param2} ")]
        return StoredPath(done.result_param2, said[0] if said else "")

    @property
    def mission_outcome(self) -> bool | None:
        """The goal dispatched last: True reached, False stopped short, None running (or
        none dispatched)."""
        return self._watch.outcome if self._watch is not None else None

    def wait_mission_done(self, timeout_s: float) -> bool:
        """Wait until the goal dispatched last is reached (``ground.mission_watch``).

        Args:
            timeout_s: how long to wait, s.

        Returns:
            True when reached; False when the run stopped short or ``timeout_s`` passed.

        Raises:
            IllegalEventError: no goal was dispatched by this station.
        """
        watch = self._watch
        if watch is None:
            raise IllegalEventError("ground station", "NO_GOAL", "wait_mission_done")
        self.run_until(lambda: watch.outcome is not None, round(timeout_s * NS_PER_S))
        return watch.outcome is True

    def send_manual_control(self, x: float, r: float, buttons: int = 0) -> None:
        """One MANUAL_CONTROL to the vehicle: ``x`` forward and ``r`` yaw (clockwise), each
        -1..1 (sent as -1000..1000); ``y`` and ``z`` are marked unused (INT16_MAX)."""
        vehicle = self._target("send_manual_control")
        self._send([mavlink.MAVLink_manual_control_message(
            vehicle.system_id, round(x * 1000), UNUSED_AXIS, UNUSED_AXIS, round(r * 1000),
            buttons)])

    # -- parameters ---------------------------------------------------------------------

    def _param_outcome(self, start: Callable[[ParamClient, int], list[Message]]) -> Any:
        self._target("parameters")
        assert self._params is not None
        self._send(start(self._params, self.clock.now_ns()))
        outcome = self._finish(self._params)
        if isinstance(outcome, ParamOperationFailed):
            name = f" {outcome.name}" if outcome.name else ""
            raise GroundError(f"parameter {outcome.operation.value}{name}: {outcome.reason}")
        return outcome

    def fetch_params(self) -> dict[str, float]:
        """Every parameter of the vehicle, by name, in its index order.

        Raises:
            GroundError: values still missing after the retries.
        """
        outcome = self._param_outcome(lambda client, now: client.fetch_all(now))
        assert isinstance(outcome, ParamsFetched)
        return outcome.values

    def get_param(self, name: str) -> float:
        """The value of parameter ``name``.

        Raises:
            GroundError: no such parameter, or no answer.
        """
        outcome = self._param_outcome(lambda client, now: client.get(name, now))
        assert isinstance(outcome, ParamReceived)
        return float(outcome.value)

    def set_param(self, name: str, value: float) -> float:
        """Set parameter ``name`` to ``value`` (REAL32).

        Returns:
            The value in force (``value`` rounded to float32).

        Raises:
            GroundError: no such parameter, no answer, or the vehicle kept another value
                (out of range...; with its reason).
        """
        vehicle = self._target("set_param")
        before = len(vehicle.notices)
        outcome = self._param_outcome(lambda client, now: client.set(name, value, now))
        assert isinstance(outcome, ParamSetDone)
        if not outcome.accepted:
            raise GroundError(f"vehicle {vehicle.system_id} kept {name} = {outcome.value:g}, "
                              f"not {value:g}{self._reason(before)}")
        return float(outcome.value)

    # -- FTP ----------------------------------------------------------------------------

    def _ftp_outcome(self, start: Callable[[int], None]) -> Any:
        self._target("ftp")
        start(self.clock.now_ns())
        self._send_ftp()
        outcome = self._finish(self._ftp)
        if isinstance(outcome, FtpFailed):
            nak = f" ({outcome.nak.name})" if outcome.nak is not None else ""
            raise GroundError(f"FTP {outcome.operation} {outcome.path}: {outcome.reason}{nak}")
        return outcome

    def ftp_list(self, path: str) -> tuple[DirEntry, ...]:
        """The entries of directory ``path`` on the vehicle.

        Raises:
            GroundError: refused (no such directory...) or unanswered.
        """
        outcome = self._ftp_outcome(lambda now: self._ftp.list_directory(path, now))
        assert isinstance(outcome, Listed)
        return outcome.entries

    def ftp_get(self, path: str) -> bytes:
        """The bytes of file ``path`` on the vehicle.

        Raises:
            GroundError: refused (no such file...) or unanswered.
        """
        outcome = self._ftp_outcome(lambda now: self._ftp.get(path, now))
        assert isinstance(outcome, Downloaded)
        return outcome.data

    def ftp_put(self, path: str, data: bytes) -> None:
        """Write ``data`` as the new file ``path`` on the vehicle.

        Raises:
            GroundError: refused (read-only area, too large...) or unanswered.
        """
        outcome = self._ftp_outcome(lambda now: self._ftp.put(path, data, now))
        assert isinstance(outcome, Uploaded)
