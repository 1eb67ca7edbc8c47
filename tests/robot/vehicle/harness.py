"""A ground station of our real client cores and the vehicle, on real UDP sockets, in
virtual time.

Every end owns a real socket on 127.0.0.1. :class:`Net` services them all at the
virtual time of a :class:`ManualClock`; while a datagram is in flight it keeps
servicing (loopback delivers within the sendto call; ``select`` waits up to
``IDLE_WAIT_S`` of real time to be sure), and when nothing is in flight it jumps
the clock to the earliest deadline of any end. So timeouts of seconds cost
milliseconds, and the order of events depends on the protocol, not on the machine.
"""

from __future__ import annotations

import random
import select
from collections.abc import Callable
from pathlib import Path
from typing import Any

from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import NS_PER_S, Clock, ManualClock
from shared.config import MavlinkConfig
from shared.mavlink.address import Address, is_for, source_of
from shared.mavlink.camera import VideoStream
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.ftp.gcs import FtpClient
from shared.mavlink.mission.gcs import MissionClient
from shared.mavlink.params.gcs import ParamClient
from shared.udp_link import UdpLink
from tests.robot.vehicle.fake_app import FakeApp

GCS = Address(255, 190)
VEHICLE = Address(1, 1)
VEHICLE_IDS = (VEHICLE.system_id, VEHICLE.component_id)
#: Real time to wait for a datagram before calling the network idle, s.
IDLE_WAIT_S = 0.002
#: Rounds of :meth:`Net.run` before it calls the run stuck.
MAX_ROUNDS = 100_000
#: Unix time at virtual time 0 (signing timestamps), ns.
UNIX_OFFSET_NS = 1_750_000_000 * NS_PER_S


def make_vehicle(root: Path, app: FakeApp, clock: Clock,
                 config: VmnavConfig | None = None, key: bytes | None = None,
                 url: str = "udpin:127.0.0.1:0", timestamp_file: Path | None = None,
                 link_warning: str | None = None, video: VideoStream | None = None,
                 failsafe_clock: Clock | None = None) -> UdpVehicle:
    """A vehicle endpoint on ``url`` with its files under ``root`` (and a camera component
    advertising ``video``, if given; its GCS failsafe on ``failsafe_clock``, if given)."""
    signing = (SigningSetup(key, UNIX_OFFSET_NS, timestamp_file=timestamp_file)
               if key is not None else None)
    files = VehicleFiles(root / "memory", root / "upload", root / "params.json")
    endpoint = VehicleEndpoint(app, config if config is not None else VmnavConfig(), files,
                               signing=signing, uid=0xC0FFEE, link_warning=link_warning,
                               video=video, failsafe_clock=failsafe_clock)
    return UdpVehicle.open(url, endpoint, clock)


class Ground:
    """A ground station: MissionClient, ParamClient and FtpClient on a real socket.

    Args:
        url: its connection string (``udpout:`` to the vehicle or a relay).
        address: its MAVLink address.
        heartbeat: send a GCS HEARTBEAT every second (set :attr:`heartbeat` later to stop).
        config: the clients' timeouts and retries.
    """

    def __init__(self, url: str, address: Address = GCS, heartbeat: bool = True,
                 config: MavlinkConfig | None = None) -> None:
        self.link = UdpLink.open(url)
        self.address = address
        self.codec = make_codec(address.system_id, address.component_id)
        self.mission = MissionClient(address, VEHICLE, config)
        self.params = ParamClient(address, VEHICLE, config)
        self.ftp = FtpClient()
        self.heartbeat = heartbeat
        self._next_heartbeat_ns = 0
        self.last_heartbeat_ns: int | None = None  # when the last GCS HEARTBEAT went out
        self.received: list[tuple[int, Message]] = []  # (virtual arrival time, message)
        self.datagrams = 0  # received, including those the codec dropped

    def send(self, *messages: Message) -> None:
        for msg in messages:
            self.link.send(self.codec.pack(msg))

    def command(self, command: int, *params: float) -> None:
        """Send COMMAND_LONG ``command`` to the vehicle (unset params NaN, as MAVSDK)."""
        p = list(params) + [float("nan")] * (7 - len(params))
        self.send(mavlink.MAVLink_command_long_message(*VEHICLE_IDS, command, 0, *p))

    def of_type(self, name: str, since_ns: int = 0) -> list[Any]:
        """Messages of type ``name`` from the vehicle received at or after ``since_ns``."""
        return [m for t, m in self.received if t >= since_ns and m.get_type() == name
                and source_of(m) == VEHICLE]

    def notices(self) -> list[str]:
        """The vehicle's STATUSTEXT notices, chunks joined (common.xml STATUSTEXT.id)."""
        texts: list[str] = []
        last_id = 0
        for msg in self.of_type("STATUSTEXT"):
            if msg.id and msg.id == last_id and msg.chunk_seq > 0:
                texts[-1] += msg.text
            else:
                texts.append(msg.text)
            last_id = msg.id
        return texts

    def service(self, now_ns: int) -> None:
        for data, _ in self.link.receive():
            self.datagrams += 1
            for msg in self.codec.parse(data):
                self.received.append((now_ns, msg))
                self.send(*self.mission.handle_message(msg, now_ns),
                          *self.params.handle_message(msg, now_ns))
                if (isinstance(msg, mavlink.MAVLink_file_transfer_protocol_message)
                        and source_of(msg) == VEHICLE and is_for(msg, self.address)):
                    self.ftp.receive_payload(msg.payload, now_ns)
        for core in (self.mission, self.params):
            timer = core.get_timer()
            if timer is not None and now_ns >= timer:
                self.send(*core.handle_timer(now_ns))
        timer = self.ftp.get_timer()
        if timer is not None and now_ns >= timer:
            self.ftp.handle_timer(now_ns)
        self.send(*(mavlink.MAVLink_file_transfer_protocol_message(0, *VEHICLE_IDS, payload)
                    for payload in self.ftp.payloads_to_send()))
        if self.heartbeat and now_ns >= self._next_heartbeat_ns:
            self.send(mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS,
                                                        mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3))
            self.last_heartbeat_ns = now_ns
            self._next_heartbeat_ns = now_ns + NS_PER_S

    def get_timer(self) -> int | None:
        timers = [self.mission.get_timer(), self.params.get_timer(), self.ftp.get_timer()]
        if self.heartbeat:
            timers.append(self._next_heartbeat_ns)
        return min((t for t in timers if t is not None), default=None)

    def close(self) -> None:
        self.link.close()


class Relay:
    """Two real sockets between the ground and a listening vehicle, dropping each datagram
    with probability ``loss`` in each direction (seeded).

    The ground sends to :attr:`port`.
    """

    def __init__(self, vehicle_port: int, loss: float, seed: int) -> None:
        self.ground_side = UdpLink.open("udpin:127.0.0.1:0")
        self.vehicle_side = UdpLink.open(f"udpout:127.0.0.1:{vehicle_port}")
        self.loss = loss
        self.rng = random.Random(seed)
        self.carried = 0
        self.dropped = 0

    @property
    def port(self) -> int:
        return self.ground_side.local_port

    def service(self, now_ns: int) -> None:
        for source, sink in ((self.ground_side, self.vehicle_side),
                             (self.vehicle_side, self.ground_side)):
            for data, _ in source.receive():
                if self.rng.random() < self.loss:
                    self.dropped += 1
                else:
                    self.carried += 1
                    sink.send(data)

    def get_timer(self) -> int | None:
        return None

    def close(self) -> None:
        self.ground_side.close()
        self.vehicle_side.close()


class Net:
    """Vehicle, optional relay and ground stations, serviced in virtual time (module docstring)."""

    def __init__(self, clock: ManualClock, vehicle: UdpVehicle, *ends: Ground | Relay) -> None:
        self.clock = clock
        self.vehicle = vehicle
        self.ends = list(ends)

    @property
    def now_ns(self) -> int:
        return self.clock.now_ns()

    @property
    def ground(self) -> Ground:
        """The first ground station."""
        return next(end for end in self.ends if isinstance(end, Ground))

    def _sockets(self) -> list[UdpLink]:
        links = [self.vehicle.link]
        for end in self.ends:
            links += [end.link] if isinstance(end, Ground) else [end.ground_side, end.vehicle_side]
        return links

    def _service(self) -> None:
        now = self.clock.now_ns()
        self.vehicle.service(now)
        for end in self.ends:
            end.service(now)

    def run(self, done: Callable[[], bool], max_s: float = 60.0,
            stop_ns: int | None = None) -> None:
        """Service everything until ``done()``, jumping virtual time while idle (never past
        ``stop_ns``).

        Raises:
            AssertionError: not done after ``max_s`` virtual seconds.
        """
        limit_ns = self.clock.now_ns() + round(max_s * NS_PER_S)
        for _ in range(MAX_ROUNDS):
            self._service()
            if done():
                return
            if select.select(self._sockets(), [], [], IDLE_WAIT_S)[0]:
                continue
            assert self.clock.now_ns() < limit_ns, f"not done after {max_s} virtual seconds"
            timers = [self.vehicle.endpoint.get_timer()] + [end.get_timer() for end in self.ends]
            self.clock.sleep_until_ns(min([t for t in timers if t is not None]
                                          + [stop_ns or limit_ns, limit_ns]))
        raise AssertionError(f"not done after {MAX_ROUNDS} rounds")

    def command(self, command: int, *params: float, final: bool = True) -> Any:
        """Send COMMAND_LONG from the ground and run until its COMMAND_ACK (with ``final``,
        the first that is not IN_PROGRESS); return the ACK."""
        ground, start = self.ground, len(self.ground.received)

        def acks() -> list[Any]:
            return [m for _, m in ground.received[start:]
                    if m.get_type() == "COMMAND_ACK" and m.command == command
                    and not (final and m.result == mavlink.MAV_RESULT_IN_PROGRESS)]

        ground.command(command, *params)
        self.run(lambda: bool(acks()))
        return acks()[0]

    def until_event(self, core: Any, max_s: float = 60.0) -> Any:
        """Run until ``core`` (a client core) reports an event; return it."""
        events: list[Any] = []

        def done() -> bool:
            event = core.next_event()
            if event is not None:
                events.append(event)
            return bool(events)

        self.run(done, max_s)
        return events[0]

    def advance(self, seconds: float) -> None:
        """Run for ``seconds`` of virtual time."""
        end_ns = self.clock.now_ns() + round(seconds * NS_PER_S)
        self.run(lambda: self.clock.now_ns() >= end_ns, seconds + 1, end_ns)

    def close(self) -> None:
        self.vehicle.close()
        for end in self.ends:
            end.close()
