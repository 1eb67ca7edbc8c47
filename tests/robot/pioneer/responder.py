"""A minimal robot end for the driver tests, and a lock-step rig around it.

:class:`Responder` is an :class:`AriaSession` in the ROBOT role that answers the
handshake with a p3at-sh identity, CONFIG with a :class:`ConfigPacket`, ENABLE by
switching its motors flag, and streams SIPs carrying the positions the test sets.
The full emulated Pioneer lives in ``sim/``; this stays small on purpose.
"""

from __future__ import annotations

from collections.abc import Callable

from robot.config import PioneerDriverConfig
from robot.pioneer.driver import PioneerDriver
from shared.aria.commands import ClientCommand, Command
from shared.aria.config_packet import ConfigPacket
from shared.aria.events import Event, SipDue
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.session import AriaSession
from shared.aria.sip import Sip, SipFlags, SipIo, wrap_position
from shared.aria.state import Role
from shared.byte_link import ByteLink, LinkClosedError, PipeEnd, pipe_pair
from shared.clock import ManualClock
from shared.config import AriaLinkConfig

MS = 1_000_000


class Responder:
    """The robot end: answers what it receives, streams SIPs on its session's timer.

    Attributes:
        x_counts, y_counts: unbounded position accumulators, counts (sent mod 0x8000).
        th_counts: heading accumulator, counts (sent mod 4096 as -2048..2047).
        received: ``(now_ns, event)`` for everything the host sent.
    """

    def __init__(self, identity: RobotIdentity | None = None,
                 config: AriaLinkConfig | None = None) -> None:
        self.identity = identity if identity is not None else RobotIdentity("vmnav", "Pioneer",
                                                                            "p3at-sh")
        self.link_config = config
        self.session = AriaSession(Role.ROBOT, config)
        self.link: ByteLink | None = None
        self.answer_syncs = True
        self.answer_config = True
        self.send_sips = True
        self.x_counts = self.y_counts = self.th_counts = 0
        self.motors = False
        self.estop = False
        self.battery_v = 12.8
        self.wheels_m_s = (0.0, 0.0)  # (left, right) as the SIP reports them
        self.rot_vel_rad_s: float | None = None  # the optional ROTVEL field
        self.bumpers = (0, 0)  # (front, rear) segment bits as the SIP reports them
        self.received: list[tuple[int, Event]] = []

    def reboot(self) -> None:
        """A fresh robot controller: new session, odometry counters at zero."""
        self.session = AriaSession(Role.ROBOT, self.link_config)
        self.x_counts = self.y_counts = self.th_counts = 0
        self.motors = False

    def sip(self) -> Sip:
        flags = SipFlags(0)
        if self.motors:
            flags |= SipFlags.MOTORS_ENABLED
        if self.estop:
            flags |= SipFlags.ESTOP_PRESSED
        tail = {} if self.rot_vel_rad_s is None else {
            "io": SipIo(), "real_battery_v": self.battery_v, "charge_state": 0,
            "rot_vel_rad_s": self.rot_vel_rad_s}
        return Sip(x_counts=wrap_position(self.x_counts), y_counts=wrap_position(self.y_counts),
                   th_counts=(self.th_counts + 2048) % 4096 - 2048,
                   left_vel_m_s=self.wheels_m_s[0], right_vel_m_s=self.wheels_m_s[1],
                   battery_v=self.battery_v, flags=flags, front_bumpers=self.bumpers[0],
                   rear_bumpers=self.bumpers[1], **tail)

    def service(self, now_ns: int) -> None:
        if self.link is None:
            return
        try:
            self.session.receive_data(self.link.read_available(), now_ns)
        except LinkClosedError:
            self.link = None
            return
        deadline = self.session.get_timer()
        if deadline is not None and now_ns >= deadline:
            self.session.handle_timer(now_ns)
        while (event := self.session.next_event()) is not None:
            self.received.append((now_ns, event))
            self._answer(event, now_ns)

    def _answer(self, event: Event, now_ns: int) -> None:
        match event:
            case SyncRequest(seq=seq) if self.answer_syncs:
                self._send(SyncReply(seq) if seq < 2 else self.identity, now_ns)
            case ClientCommand(command=Command.CONFIG) if self.answer_config:
                self._send(ConfigPacket(), now_ns)
            case ClientCommand(command=Command.ENABLE, arg=arg):
                self.motors = arg == 1 and not self.estop
            case SipDue() if self.send_sips:
                self._send(self.sip(), now_ns)

    def _send(self, event: object, now_ns: int) -> None:
        assert self.link is not None
        self.link.write(self.session.send(event, now_ns))  # type: ignore[arg-type]

    def commands(self, command: Command) -> list[tuple[int, ClientCommand]]:
        """``(now_ns, event)`` of every ``command`` received."""
        return [(t, e) for t, e in self.received
                if isinstance(e, ClientCommand) and e.command is command]


class RecordingLink:
    """A real pipe end that also keeps what the driver wrote through it."""

    def __init__(self, end: PipeEnd) -> None:
        self.end = end
        self.written = bytearray()

    def write(self, data: bytes) -> None:
        self.end.write(data)
        self.written += data

    def read_available(self) -> bytes:
        return self.end.read_available()

    def close(self) -> None:
        self.end.close()


class Rig:
    """A driver and a responder joined by in-memory pipes, stepped on one ManualClock.

    Each call of the driver's link factory makes a new pipe and hands the robot end to
    the same responder, whose session survives (a serial robot whose port is re-opened)
    unless the test reboots it.
    """

    def __init__(self, config: PioneerDriverConfig | None = None,
                 responder: Responder | None = None) -> None:
        self.clock = ManualClock()
        self.config = config if config is not None else PioneerDriverConfig()
        self.responder = responder if responder is not None else Responder(
            config=self.config.link)
        self.links: list[RecordingLink] = []
        self.driver = PioneerDriver(self._open, self.clock, self.config)

    def _open(self) -> RecordingLink:
        host_end, robot_end = pipe_pair()
        self.responder.link = robot_end
        self.links.append(RecordingLink(host_end))
        return self.links[-1]

    def step(self, step_ms: int = 10) -> None:
        now_ns = self.clock.now_ns()
        self.driver.service(now_ns)
        self.responder.service(now_ns)
        self.clock.advance_ns(step_ms * MS)

    def run(self, seconds: float, step_ms: int = 10) -> None:
        for _ in range(round(seconds * 1000 / step_ms)):
            self.step(step_ms)

    def run_until(self, done: Callable[[], bool], timeout_s: float = 30.0) -> None:
        deadline_ns = self.clock.now_ns() + round(timeout_s * 1e9)
        while not done():
            assert self.clock.now_ns() < deadline_ns, "condition not reached in time"
            self.step()

    def connect(self) -> None:
        """Run until the driver accepts commands."""
        self.run_until(lambda: self.driver.status().motors_enabled)

    def events(self) -> list[object]:
        out = []
        while (event := self.driver.next_event()) is not None:
            out.append(event)
        return out
