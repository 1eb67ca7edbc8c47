"""AriaSession: both ends in memory, the connect state machine, timers (reference §3, §7)."""

from __future__ import annotations

import math

import pytest

from shared.aria.commands import ClientCommand, Command, enable, vel
from shared.aria.config_packet import ConfigPacket
from shared.aria.events import (
    ConnectFailed,
    LinkLost,
    RawPacket,
    SipDue,
    UnexpectedPacket,
    WatchdogCleared,
    WatchdogExpired,
)
from shared.aria.framing import CorruptPacket
from shared.aria.handshake import RobotIdentity, SyncReply, SyncRequest
from shared.aria.session import AriaSession
from shared.aria.sip import Sip, SipFlags, SipType
from shared.aria.state import ConnState, Role
from shared.clock import ManualClock
from shared.config import AriaLinkConfig, from_mapping
from shared.errors import ConfigError, LocalProtocolError
from tests.shared.aria.helpers import flip_checksum_byte, golden, hexbytes, random_chunks

MS = 1_000_000
OPEN_1 = ClientCommand(Command.OPEN, 1)
CLOSE_1 = ClientCommand(Command.CLOSE, 1)


class Pair:
    """A HOST and a ROBOT session joined by in-memory pipes, timed by one ManualClock."""

    def __init__(self, clock: ManualClock, config: AriaLinkConfig | None = None) -> None:
        self.clock = clock
        self.host = AriaSession(Role.HOST, config)
        self.robot = AriaSession(Role.ROBOT, config)

    def host_sends(self, event: object) -> None:
        self.robot.receive_data(self.host.send(event, self.clock.now_ns()), self.clock.now_ns())

    def robot_sends(self, event: object) -> None:
        self.host.receive_data(self.robot.send(event, self.clock.now_ns()), self.clock.now_ns())

    def connect(self) -> None:
        """Handshake and OPEN, each end answering what it receives as ARIA/ARCOS do."""
        self.host_sends(SyncRequest(0))
        for seq in (0, 1, 2):
            assert drain(self.robot) == [SyncRequest(seq)]
            self.robot_sends(SyncReply(seq) if seq < 2 else RobotIdentity())
            reply = drain(self.host)
            assert reply == [SyncReply(seq) if seq < 2 else RobotIdentity()]
            self.host_sends(SyncRequest(seq + 1) if seq < 2 else OPEN_1)
        assert drain(self.robot) == [OPEN_1]


def drain(session: AriaSession) -> list:
    events = []
    while (event := session.next_event()) is not None:
        events.append(event)
    return events


@pytest.fixture
def pair(manual_clock: ManualClock) -> Pair:
    return Pair(manual_clock)


def test_connect_open_run_close(pair: Pair) -> None:
    pair.connect()
    assert pair.host.state is pair.robot.state is ConnState.OPEN
    assert pair.host.identity == pair.robot.identity == RobotIdentity()
    assert pair.robot.get_timer() == pair.clock.now_ns()  # the first SIP is due at OPEN
    pair.robot.handle_timer(pair.clock.now_ns())
    assert drain(pair.robot) == [SipDue(pair.clock.now_ns())]
    pair.robot_sends(Sip())
    assert drain(pair.host) == [Sip()]
    pair.host_sends(enable(True))
    assert drain(pair.robot) == [enable(True)]
    assert pair.host.state is ConnState.OPEN  # RUNNING is what the robot reports
    running = Sip(sip_type=SipType.MOVING, flags=SipFlags.MOTORS_ENABLED, left_vel_m_s=0.2)
    pair.robot_sends(running)
    assert drain(pair.host) == [running]
    assert pair.host.state is pair.robot.state is ConnState.RUNNING
    pair.robot_sends(ConfigPacket())
    assert drain(pair.host) == [ConfigPacket()]
    pair.host_sends(CLOSE_1)
    assert drain(pair.robot) == [CLOSE_1]
    assert pair.host.state is pair.robot.state is ConnState.CLOSED
    assert pair.host.bad_checksums == pair.robot.bad_checksums == 0


def test_aria_connect_bytes_over_serial(manual_clock: ManualClock, rng) -> None:
    # Reference §3: WMS2\r, SYNC0-2, OPEN 1, CONFIG 1, BATTERYINFO 1 as ARIA sends them,
    # cut into random chunks; the robot's replies must be the bytes ARIA expects.
    robot = AriaSession(Role.ROBOT)
    stream = hexbytes(golden()["wms2"]["bytes"]) + hexbytes(
        "FA FB 03 00 00 00  FA FB 03 01 00 01  FA FB 03 02 00 02  FA FB 06 01 3B 01 00 02 3B"
        "FA FB 06 12 3B 01 00 13 3B  FA FB 06 3E 3B 01 00 3F 3B"
    )
    replies, events = [], []
    for chunk in random_chunks(stream, rng, max_chunk=4):
        robot.receive_data(chunk, manual_clock.now_ns())
        for event in drain(robot):
            events.append(event)
            if isinstance(event, SyncRequest):
                answer = SyncReply(event.seq) if event.seq < 2 else RobotIdentity()
                replies.append(robot.send(answer, manual_clock.now_ns()))
    assert events == [SyncRequest(0), SyncRequest(1), SyncRequest(2), OPEN_1,
                      ClientCommand(Command.CONFIG, 1), ClientCommand(Command.BATTERYINFO, 1)]
    assert replies == [hexbytes("FA FB 03 00 00 00"), hexbytes("FA FB 03 01 00 01"),
                       hexbytes(golden()["sync2_replies"][0]["frame"])]
    assert robot.state is ConnState.OPEN and robot.skipped_bytes == 5


def test_p2os_open_without_argument(pair: Pair) -> None:
    pair.host_sends(SyncRequest(0))
    for seq in (0, 1, 2):
        drain(pair.robot)
        pair.robot_sends(SyncReply(seq) if seq < 2 else RobotIdentity())
        drain(pair.host)
        if seq < 2:
            pair.host_sends(SyncRequest(seq + 1))
    pair.robot.receive_data(hexbytes("FA FB 03 01 00 01"), pair.clock.now_ns())
    assert drain(pair.robot) == [ClientCommand(Command.OPEN)]
    assert pair.robot.state is ConnState.OPEN


@pytest.mark.parametrize(
    ("role", "event", "state"),
    [
        (Role.HOST, vel(0.1), "WAIT_SYNC0"),
        (Role.HOST, SyncRequest(1), "WAIT_SYNC0"),
        (Role.HOST, Sip(), "WAIT_SYNC0"),
        (Role.ROBOT, SyncReply(0), "WAIT_SYNC0"),
        (Role.ROBOT, Sip(), "WAIT_SYNC0"),
        (Role.ROBOT, vel(0.1), "WAIT_SYNC0"),
    ],
)
def test_illegal_send_names_event_and_state(role: Role, event: object, state: str) -> None:
    session = AriaSession(role)
    pattern = rf"{role.name} cannot send {type(event).__name__}\(.* in state {state}"
    with pytest.raises(LocalProtocolError, match=pattern):
        session.send(event, 0)
    assert session.state is ConnState.WAIT_SYNC0


def test_illegal_sends_after_handshake(pair: Pair) -> None:
    pair.host_sends(SyncRequest(0))
    drain(pair.robot)
    pair.robot_sends(SyncReply(0))
    drain(pair.host)
    with pytest.raises(LocalProtocolError, match="in state WAIT_SYNC1"):
        pair.robot.send(SyncReply(1), 0)  # nothing requested yet
    pair.connect()  # a SYNC0 restarts the handshake from any state before OPEN
    with pytest.raises(LocalProtocolError, match="in state OPEN"):
        pair.host.send(SyncRequest(0), 0)
    with pytest.raises(LocalProtocolError, match="ROBOT cannot send ClientCommand"):
        pair.robot.send(vel(0.0), 0)
    with pytest.raises(LocalProtocolError, match="HOST cannot send UnexpectedPacket"):
        pair.host.send(UnexpectedPacket(OPEN_1.to_packet(), "x"), 0)


def test_no_sip_and_no_pulse_before_open(pair: Pair) -> None:
    pair.host_sends(SyncRequest(0))
    for seq in (0, 1, 2):
        drain(pair.robot)
        pair.robot_sends(SyncReply(seq) if seq < 2 else RobotIdentity())
        drain(pair.host)
        if seq < 2:
            pair.host_sends(SyncRequest(seq + 1))
    assert pair.robot.state is ConnState.CONNECTED
    with pytest.raises(LocalProtocolError, match=r"ROBOT cannot send Sip\(.* in state CONNECTED"):
        pair.robot.send(Sip(), 0)
    with pytest.raises(LocalProtocolError, match="in state CONNECTED"):
        pair.host.send(ClientCommand(Command.PULSE), 0)  # would read as a SYNC0 restart


def test_out_of_sequence_sync_restarts_the_robot(pair: Pair) -> None:
    pair.host_sends(SyncRequest(0))
    drain(pair.robot)
    pair.robot_sends(SyncReply(0))
    pair.robot.receive_data(SyncRequest(2).to_packet().to_bytes(), 0)
    (event,) = drain(pair.robot)
    assert isinstance(event, UnexpectedPacket) and "WAIT_SYNC1" in event.reason
    assert pair.robot.state is ConnState.WAIT_SYNC0


def test_host_retries_sync0_then_fails(manual_clock: ManualClock) -> None:
    config = AriaLinkConfig(sync_attempts=3)
    host = AriaSession(Role.HOST, config)
    sent = [host.send(SyncRequest(0), manual_clock.now_ns())]
    while (deadline := host.get_timer()) is not None:
        manual_clock.sleep_until_ns(deadline)
        if data := host.handle_timer(manual_clock.now_ns()):
            sent.append(data)
    assert sent == [SyncRequest(0).to_packet().to_bytes()] * 3
    assert drain(host) == [ConnectFailed(3)]
    assert host.state is ConnState.CLOSED and manual_clock.now_ns() == 3 * 1000 * MS


def test_host_restarts_at_sync0_when_a_later_reply_is_overdue(pair: Pair) -> None:
    pair.host_sends(SyncRequest(0))
    drain(pair.robot)
    pair.robot_sends(SyncReply(0))
    drain(pair.host)
    pair.host_sends(SyncRequest(1))  # the robot's echo gets lost
    pair.clock.advance_ns(999 * MS)
    assert pair.host.handle_timer(pair.clock.now_ns()) == b""
    pair.clock.advance_ns(MS)
    assert pair.host.handle_timer(pair.clock.now_ns()) == SyncRequest(0).to_packet().to_bytes()
    assert pair.host.state is ConnState.SYNC0_REQUESTED


def test_host_pulses_and_robot_watchdog_stays_quiet(pair: Pair) -> None:
    pair.connect()
    pulses = 0
    for _ in range(40):  # 4 s, robot streaming SIPs, host idle
        pair.clock.advance_ns(100 * MS)
        pair.robot.handle_timer(pair.clock.now_ns())
        for event in drain(pair.robot):
            assert not isinstance(event, WatchdogExpired)
            if isinstance(event, SipDue):
                pair.robot_sends(Sip())
        drain(pair.host)
        if data := pair.host.handle_timer(pair.clock.now_ns()):
            pulses += 1
            pair.robot.receive_data(data, pair.clock.now_ns())
    assert pulses == 8  # one per 500 ms of silence (ARIA, reference §7)
    assert pair.host.state is pair.robot.state is ConnState.OPEN


def test_robot_watchdog_expires_then_clears(pair: Pair) -> None:
    pair.connect()
    pair.clock.advance_ns(1999 * MS)
    pair.robot.handle_timer(pair.clock.now_ns())
    assert not any(isinstance(e, WatchdogExpired) for e in drain(pair.robot))
    pair.clock.advance_ns(MS)
    pair.robot.handle_timer(pair.clock.now_ns())
    assert WatchdogExpired(2000 * MS) in drain(pair.robot)
    pair.clock.advance_ns(500 * MS)
    pair.robot.handle_timer(pair.clock.now_ns())
    assert not any(isinstance(e, WatchdogExpired) for e in drain(pair.robot))  # once per silence
    pair.host_sends(vel(0.2))
    assert drain(pair.robot) == [WatchdogCleared(), vel(0.2)]


def test_sip_cadence_keeps_its_grid_and_does_not_burst(pair: Pair) -> None:
    pair.connect()
    t0 = pair.clock.now_ns()
    due = []
    for offset_ms in (0, 100, 230, 300, 750):
        pair.clock.sleep_until_ns(t0 + offset_ms * MS)
        pair.robot.handle_timer(pair.clock.now_ns())
        due += [e.deadline_ns - t0 for e in drain(pair.robot) if isinstance(e, SipDue)]
    assert due == [0, 100 * MS, 200 * MS, 300 * MS, 400 * MS]
    assert pair.robot.get_timer() == t0 + 850 * MS  # re-anchored after falling behind


def test_host_detects_link_loss(pair: Pair) -> None:
    pair.connect()
    pair.robot_sends(Sip())
    drain(pair.host)
    pair.clock.advance_ns(8000 * MS)
    pair.host.handle_timer(pair.clock.now_ns())
    assert drain(pair.host) == [LinkLost(8000 * MS)]
    assert pair.host.state is ConnState.CLOSED and pair.host.get_timer() is None


def test_serial_reconnect_after_close(pair: Pair) -> None:
    pair.connect()
    pair.host_sends(CLOSE_1)
    drain(pair.robot)
    pair.connect()
    assert pair.host.state is pair.robot.state is ConnState.OPEN


def test_stale_robot_is_closed_then_resynced(manual_clock: ManualClock) -> None:
    # Reference §3: a robot still streaming 0x32 SIPs to a dead client; the new client
    # sees a SIP instead of its SYNC0 echo, sends CLOSE, then syncs again.
    old = Pair(manual_clock)
    old.connect()
    robot, host = old.robot, AriaSession(Role.HOST)
    robot.receive_data(host.send(SyncRequest(0), 0), 0)
    assert drain(robot) == [ClientCommand(Command.PULSE)]  # SYNC0 reads as PULSE while open
    host.receive_data(robot.send(Sip(), 0), 0)
    (event,) = drain(host)
    assert isinstance(event, UnexpectedPacket) and event.packet.packet_id == 0x32
    assert "SYNC0_REQUESTED" in event.reason
    robot.receive_data(host.send(CLOSE_1, 0), 0)
    assert drain(robot) == [CLOSE_1] and robot.state is ConnState.CLOSED
    assert host.state is ConnState.WAIT_SYNC0
    robot.receive_data(host.send(SyncRequest(0), 0), 0)
    assert drain(robot) == [SyncRequest(0)]


def test_corrupt_and_unknown_packets_are_never_fatal(pair: Pair) -> None:
    pair.connect()
    good = vel(0.3).to_packet().to_bytes()
    pair.robot.receive_data(flip_checksum_byte(good, 0) + b"\xfa\xfb\x03\x93\x00\x93" + good, 0)
    first, second, third = drain(pair.robot)
    assert isinstance(first, CorruptPacket) and first.packet_id == Command.VEL
    assert isinstance(second, UnexpectedPacket) and "unknown command number 147" in second.reason
    assert third == vel(0.3) and pair.robot.bad_checksums == 1
    pair.robot_sends(RawPacket(0xF0, b"\x00\x00\x00"))
    assert drain(pair.host) == [RawPacket(0xF0, b"\x00\x00\x00")]
    pair.host.receive_data(RawPacket(0x32, b"short").to_packet().to_bytes(), 0)
    (malformed,) = drain(pair.host)
    assert isinstance(malformed, UnexpectedPacket)
    assert "shorter than its fixed part" in malformed.reason
    assert pair.host.state is ConnState.OPEN


def test_partial_frame_is_abandoned_after_the_frame_timeout(manual_clock: ManualClock) -> None:
    robot = AriaSession(Role.ROBOT)
    robot.receive_data(b"\xfa\xfb\xf0junk" + SyncRequest(0).to_packet().to_bytes(), 0)
    assert drain(robot) == [] and robot.get_timer() == 100 * MS
    robot.handle_timer(99 * MS)
    assert drain(robot) == []
    robot.handle_timer(100 * MS)
    assert drain(robot) == [SyncRequest(0)] and robot.abandoned_frames == 1
    assert robot.get_timer() is None


def test_config_loads_and_is_validated() -> None:
    loaded = from_mapping(AriaLinkConfig, {"sync_attempts": 3}, "link.toml", "aria")
    assert loaded == AriaLinkConfig(sync_attempts=3)
    with pytest.raises(ConfigError, match=r"link\.toml: aria: sync_attempts must be >= 1, got 0"):
        from_mapping(AriaLinkConfig, {"sync_attempts": 0}, "link.toml", "aria")
    with pytest.raises(ValueError, match="watchdog_timeout_ns must be > 0"):
        AriaLinkConfig(watchdog_timeout_ns=0)


def test_heading_helpers_reach_the_robot_in_si(pair: Pair) -> None:
    pair.connect()
    pair.host_sends(ClientCommand(Command.HEAD, -90))  # ARIA sends negative headings
    (head,) = drain(pair.robot)
    assert head.si_value == pytest.approx(-math.pi / 2)
