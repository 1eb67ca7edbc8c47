"""PioneerDriver in lock-step over in-memory pipes against a minimal robot end."""

from __future__ import annotations

import itertools
import math

import pytest

from robot.config import PioneerDriverConfig
from robot.pioneer.driver import PioneerDriver
from robot.pioneer.events import (
    Closed,
    CommandExpired,
    Connected,
    ConnectFailed,
    EStopPressed,
    EStopReleased,
    LinkLost,
    MotorsDisabled,
    MotorsEnabled,
    Reconnecting,
    StaleStream,
    TransportFailed,
    UnknownSubtype,
)
from robot.pioneer.status import LinkState
from shared.aria.commands import ClientCommand, Command
from shared.aria.config_packet import ConfigPacket
from shared.aria.events import RawPacket
from shared.aria.handshake import RobotIdentity, SyncRequest
from shared.config import AriaLinkConfig
from shared.errors import LocalProtocolError, TransportError
from shared.interfaces import MobileBase
from tests.robot.pioneer.responder import MS, RecordingLink, Responder, Rig

S = 1_000_000_000


def args_of(rig: Rig, command: Command) -> list[object]:
    return [e.arg for _, e in rig.responder.commands(command)]


def test_is_a_mobile_base() -> None:
    assert isinstance(Rig().driver, MobileBase)


def test_handshake_sends_arias_connect_sequence() -> None:
    rig = Rig()
    rig.connect()
    host_events = [e for _, e in rig.responder.received]
    assert host_events[:3] == [SyncRequest(0), SyncRequest(1), SyncRequest(2)]
    sent = [e.command for e in host_events[3:] if isinstance(e, ClientCommand)]
    assert sent[:11] == [Command.OPEN, Command.CONFIG, Command.SETV, Command.SETA, Command.SETA,
                         Command.SETRV, Command.SETRA, Command.SETRA, Command.VEL, Command.RVEL,
                         Command.ENABLE]
    assert args_of(rig, Command.SETV) == [600]  # mm/s
    assert args_of(rig, Command.SETA) == [300, -600]  # mm/s², accel then decel
    assert args_of(rig, Command.SETRV) == [43]  # deg/s
    assert args_of(rig, Command.ENABLE) == [1]
    events = rig.events()
    connected = [e for e in events if isinstance(e, Connected)]
    assert connected == [Connected(RobotIdentity("vmnav", "Pioneer", "p3at-sh"), ConfigPacket())]
    assert MotorsEnabled() in events
    state = rig.driver.state()
    assert state.motors_enabled and state.battery_v == pytest.approx(12.8)
    assert state.odom_pose == (0.0, 0.0, 0.0)
    assert rig.driver.counters().connects == 1


def test_motion_limits_are_capped_by_the_configs_tops() -> None:
    rig = Rig(PioneerDriverConfig(max_speed_m_s=1.5))  # ConfigPacket's TransVelTop is 1.0 m/s
    rig.connect()
    assert args_of(rig, Command.SETV) == [1000]


def test_sync_retries_until_the_robot_answers() -> None:
    rig = Rig()
    rig.responder.answer_syncs = False
    rig.run(2.5)
    rig.responder.answer_syncs = True
    rig.connect()
    sync0_times = [t for t, e in rig.responder.received if e == SyncRequest(0)]
    assert sync0_times == [0, 1 * S, 2 * S, 3 * S]  # one per sync_reply_timeout
    assert len(rig.links) == 1


def test_connect_fails_after_the_configured_attempts_then_reopens() -> None:
    config = PioneerDriverConfig(link=AriaLinkConfig(sync_attempts=3))
    rig = Rig(config)
    rig.responder.answer_syncs = False
    rig.run(3.5)
    events = rig.events()
    assert ConnectFailed(3) in events
    assert Reconnecting(1, config.reconnect_initial_ns) in events
    assert rig.driver.status().link is LinkState.DISCONNECTED
    rig.responder.answer_syncs = True
    rig.connect()
    assert len(rig.links) == 2


def test_without_config_reply_it_connects_after_the_wait() -> None:
    rig = Rig()
    rig.responder.answer_config = False
    rig.connect()
    config_times = [t for t, _ in rig.responder.commands(Command.CONFIG)]
    assert len(config_times) == 5  # at 0, 200, 400, 600, 800 ms after OPEN
    assert all(b - a == 200 * MS for a, b in itertools.pairwise(config_times))
    connected = [e for e in rig.events() if isinstance(e, Connected)]
    assert connected[0].config is None


def test_keep_alive_pulses_at_most_500_ms_apart() -> None:
    rig = Rig()
    rig.connect()
    start_ns = rig.clock.now_ns()
    rig.run(2.0)
    pulses = [t for t, _ in rig.responder.commands(Command.PULSE) if t >= start_ns]
    gaps = [b - a for a, b in itertools.pairwise([start_ns, *pulses])]
    assert len(pulses) >= 4
    assert max(gaps) <= 500 * MS


def test_command_writes_vel_and_rvel_bytes() -> None:
    rig = Rig()
    rig.connect()
    link = rig.links[-1]
    link.written.clear()
    rig.driver.command(0.2, math.radians(10))
    rig.step()
    vel_200 = bytes.fromhex("FA FB 06 0B 3B C8 00 D3 3B")  # reference §3 table
    rvel_10 = bytes.fromhex("FA FB 06 15 3B 0A 00 1F 3B")
    assert bytes(link.written) == vel_200 + rvel_10
    rig.driver.command(0.2, math.radians(10))  # unchanged: nothing new on the wire
    rig.step()
    assert bytes(link.written) == vel_200 + rvel_10
    for _ in range(5):  # a loop repeating its command at 10 Hz
        rig.driver.command(0.2, math.radians(10))
        rig.run(0.1)
    # ARIA's 500 ms state reflection re-sends a non-zero command.
    assert bytes(link.written).count(vel_200) == 2


def test_stop_sends_zero_velocities_and_refresh_ends() -> None:
    rig = Rig()
    rig.connect()
    rig.driver.command(-0.2, -0.1)
    rig.step()
    rig.driver.stop()
    rig.run(2.0)
    # Connect, command, stop; no refresh once the robot reports its wheels stopped.
    assert args_of(rig, Command.VEL) == [0, -200, 0]
    assert args_of(rig, Command.RVEL) == [0, -6, 0]


def test_a_command_not_repeated_expires_to_zero_until_the_next_one() -> None:
    rig = Rig()
    rig.connect()
    rig.events()
    given_ns = rig.clock.now_ns()
    rig.driver.command(0.2, math.radians(10))
    rig.run(0.29)
    assert args_of(rig, Command.VEL) == [0, 200] and rig.events() == []
    rig.run(0.02)  # the limit, 300 ms, passes: zero goes out at once, not a refresh
    assert args_of(rig, Command.VEL) == [0, 200, 0]
    assert args_of(rig, Command.RVEL) == [0, 10, 0]
    (stop_ns, _), = rig.responder.commands(Command.VEL)[-1:]
    assert given_ns + 300 * MS <= stop_ns <= given_ns + 310 * MS
    expired = rig.events()
    assert len(expired) == 1 and isinstance(expired[0], CommandExpired)
    assert expired[0].limit_ns == 300 * MS and "stopped until the next command" in str(expired[0])
    assert rig.driver.counters().expired_commands == 1
    rig.run(2.0)  # the robot reports its wheels still: nothing more, the old command stays dead
    assert args_of(rig, Command.VEL) == [0, 200, 0]
    rig.driver.command(0.2, math.radians(10))  # a new command resumes at once
    rig.step()
    assert args_of(rig, Command.VEL) == [0, 200, 0, 200]


def test_a_repeated_command_never_expires_and_a_stop_needs_no_repeat() -> None:
    rig = Rig(PioneerDriverConfig(command_timeout_ns=150 * MS))
    rig.connect()
    for _ in range(30):  # 3 s at 10 Hz, each repeat well within the limit
        rig.driver.command(0.2, 0.0)
        rig.run(0.1)
    assert args_of(rig, Command.VEL) == [0, 200, 200, 200, 200, 200, 200]  # connect, refreshes
    rig.driver.stop()
    rig.run(2.0)
    assert args_of(rig, Command.VEL)[-1] == 0
    assert rig.driver.counters().expired_commands == 0
    assert not any(isinstance(e, CommandExpired) for e in rig.events())


def test_measured_velocities_and_refresh_until_the_wheels_stop() -> None:
    rig = Rig()
    rig.connect()
    rig.responder.wheels_m_s = (0.099, 0.201)  # reference §5's example SIP
    rig.run(0.2)
    status = rig.driver.status()
    assert status.v_m_s == pytest.approx(0.150)
    assert status.omega_rad_s == pytest.approx(51 * 0.0034)  # (R - L) / 2 x DiffConvFactor
    rig.responder.rot_vel_rad_s = math.radians(10.0)
    rig.run(0.2)
    assert rig.driver.status().omega_rad_s == pytest.approx(math.radians(10.0))
    rig.run(1.0)  # commanded zero, still rolling: VEL 0 / RVEL 0 go out again every 500 ms
    assert args_of(rig, Command.VEL) == [0, 0, 0, 0]
    rig.responder.wheels_m_s = (0.0, 0.0)
    rig.run(1.0)
    assert args_of(rig, Command.VEL) == [0, 0, 0, 0]
    with pytest.raises(LocalProtocolError, match="must be finite"):
        rig.driver.command(math.nan, 0.0)


@pytest.mark.parametrize(("bumpers", "bumped", "rear_only"), [
    ((0, 0), False, False), ((0x01, 0), True, False), ((0, 0x10), True, True),
    ((0x04, 0x02), True, False)])
def test_the_state_tells_the_rear_bumper_from_the_front(
        bumpers: tuple[int, int], bumped: bool, rear_only: bool) -> None:
    rig = Rig()
    rig.connect()
    rig.responder.bumpers = bumpers
    rig.run(0.2)
    state = rig.driver.state()
    assert (state.bumped, state.bumped_rear_only) == (bumped, rear_only)


def test_link_loss_stops_reconnects_and_odometry_continues() -> None:
    rig = Rig()
    rig.connect()
    for _ in range(10):
        rig.responder.x_counts += 100
        rig.run(0.1)
    rig.driver.command(0.3, 0.0)
    rig.run(0.2)
    before = rig.driver.state().odom_pose
    assert before == pytest.approx((1.0, 0.0, 0.0))
    rig.responder.send_sips = False
    rig.run(8.0)
    events = rig.events()
    lost = [e for e in events if isinstance(e, LinkLost)]
    assert len(lost) == 1 and "no SIP for 8.0 s" in lost[0].reason
    # Sent past the ended session in case the robot still hears us.
    host = [e for _, e in rig.responder.received if isinstance(e, ClientCommand)]
    assert host[-3:] == [ClientCommand(Command.VEL, 0), ClientCommand(Command.RVEL, 0),
                         ClientCommand(Command.CLOSE, 1)]
    status = rig.driver.status()
    assert status.link is LinkState.DISCONNECTED
    assert not rig.driver.state().motors_enabled and status.v_m_s == 0.0
    rig.driver.command(0.5, 0.0)  # while disconnected: dropped, never sent later
    assert rig.driver.counters().dropped_commands == 1
    vels_before = len(args_of(rig, Command.VEL))
    rig.responder.reboot()  # the robot comes back with other odometry counters
    rig.responder.x_counts, rig.responder.th_counts = -5000, 1024  # heading 90 deg
    rig.responder.send_sips = True
    rig.connect()
    assert len(rig.links) == 2
    assert rig.driver.state().odom_pose == pytest.approx(before)  # no jump
    rig.responder.y_counts += 250  # forward, in the robot's own frame
    rig.run(0.2)
    assert rig.driver.state().odom_pose == pytest.approx((before[0] + 0.25, 0.0, 0.0), abs=1e-5)
    assert args_of(rig, Command.VEL)[vels_before:] == [0]  # explicit stop; no lurch


def test_link_closed_on_write_reconnects_through_a_stale_stream() -> None:
    rig = Rig()
    rig.connect()
    rig.responder.x_counts = 700
    rig.run(0.2)
    before = rig.driver.state().odom_pose
    rig.responder.link.write(rig.responder.session.send(rig.responder.sip(), rig.clock.now_ns()))
    rig.links[-1].end.close()  # the SIP stays readable, so the read works and the write fails
    rig.driver.command(0.1, 0.0)
    rig.driver.service(rig.clock.now_ns())
    events = rig.events()
    assert any(isinstance(e, LinkLost) and "pipe" in e.reason for e in events)
    # The robot never saw CLOSE: its session still streams SIPs and answers SYNC0 as PULSE.
    rig.connect()
    assert StaleStream() in rig.events()
    assert len(rig.links) == 2
    assert rig.driver.state().odom_pose == pytest.approx(before)


def test_reset_notice_loses_the_link() -> None:
    rig = Rig()
    rig.connect()
    rig.responder.link.write(rig.responder.session.send(RawPacket(0xFF), rig.clock.now_ns()))
    rig.step()
    assert LinkLost("the robot announced a controller reset (packet 0xFF)") in rig.events()


def test_a_client_bug_is_counted_and_the_link_rebuilt(monkeypatch: pytest.MonkeyPatch) -> None:
    rig = Rig()
    rig.connect()
    client = rig.driver._client

    def broken(data: bytes, now_ns: int) -> None:
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(client, "receive_data", broken)
    rig.step()
    rig.step()  # the thread's next round: no exception escapes
    assert rig.driver.faults.counts() == {"ARIA round: ZeroDivisionError": 1}
    assert LinkLost("internal error (ZeroDivisionError)") in rig.events()
    monkeypatch.undo()
    rig.connect()
    assert len(rig.links) == 2 and rig.driver.state() is not None


def test_factory_failures_back_off_and_retry_forever() -> None:
    rig = Rig(PioneerDriverConfig(reconnect_initial_ns=100 * MS, reconnect_max_ns=400 * MS))
    failures = []

    def refuse() -> RecordingLink:
        failures.append(rig.clock.now_ns())
        if len(failures) <= 5:
            raise TransportError("socket://robot:8101", "connection refused")
        return rig._open()

    rig.driver = PioneerDriver(refuse, rig.clock, rig.config)
    rig.connect()
    assert failures == [0, 100 * MS, 300 * MS, 700 * MS, 1100 * MS, 1500 * MS]
    events = rig.events()
    assert events.count(TransportFailed("socket://robot:8101", "connection refused")) == 5
    assert [e.delay_ns for e in events if isinstance(e, Reconnecting)] == [
        100 * MS, 200 * MS, 400 * MS, 400 * MS, 400 * MS]


def test_estop_disables_motion_until_re_enabled() -> None:
    rig = Rig()
    rig.connect()
    rig.events()
    rig.driver.command(0.2, 0.0)
    rig.step()
    rig.responder.estop, rig.responder.motors = True, False
    rig.run(0.2)
    assert rig.events() == [EStopPressed(), MotorsDisabled()]
    assert args_of(rig, Command.VEL) == [0, 200, 0]  # the command was reset
    rig.driver.command(0.2, 0.0)
    assert not rig.driver.state().motors_enabled
    assert rig.driver.counters().dropped_commands == 1
    rig.responder.estop = False
    rig.run(0.2)
    assert rig.events() == [EStopReleased()]
    assert not rig.driver.state().motors_enabled  # a human re-arms it
    rig.driver.enable_motors()
    rig.run(0.3)
    assert rig.events() == [MotorsEnabled()]
    assert rig.driver.state().motors_enabled


def test_e_stop_sends_e_stop_then_zero_velocity() -> None:
    rig = Rig()
    rig.connect()
    rig.driver.command(0.2, 0.0)
    rig.step()
    rig.driver.e_stop()
    rig.step()
    host = [e.command for _, e in rig.responder.received if isinstance(e, ClientCommand)]
    assert host[-3:] == [Command.E_STOP, Command.VEL, Command.RVEL]
    assert args_of(rig, Command.VEL)[-1] == 0


def test_unknown_subtype_uses_p3at_sh_factors() -> None:
    rig = Rig(responder=Responder(RobotIdentity("x", "Pioneer", "p9zz")))
    rig.connect()
    assert UnknownSubtype("p9zz", "p3at-sh") in rig.events()
    rig.responder.x_counts += 1000
    rig.run(0.2)
    assert rig.driver.state().odom_pose[0] == pytest.approx(1.0)


def test_close_sends_stop_and_close_and_is_idempotent() -> None:
    rig = Rig()
    rig.connect()
    rig.driver.command(0.2, 0.0)
    rig.step()
    rig.driver.close()
    rig.responder.service(rig.clock.now_ns())
    host = [e for _, e in rig.responder.received if isinstance(e, ClientCommand)]
    assert host[-4:] == [ClientCommand(Command.VEL, 0), ClientCommand(Command.RVEL, 0),
                         ClientCommand(Command.ENABLE, 0), ClientCommand(Command.CLOSE, 1)]
    assert Closed() in rig.events()
    assert rig.driver.status().link is LinkState.CLOSED
    rig.driver.close()
    rig.run(1.0)  # service after close does nothing
    assert len(rig.links) == 1 and rig.responder.link is None  # the pipe was released


def test_wait_connected_services_the_link_without_a_thread() -> None:
    rig = Rig()
    rig.responder.answer_syncs = False
    assert not rig.driver.wait_connected(500 * MS)  # no robot end is served meanwhile
    assert rig.clock.now_ns() == 500 * MS


def test_sip_observers_see_every_sip_and_a_failing_one_is_logged_once(
        caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig()
    seen: list[tuple[int, object]] = []

    def failing(now_ns: int, sip: object) -> None:
        raise RuntimeError("the log is broken")

    rig.driver.sip_observers.extend([failing, lambda now_ns, sip: seen.append((now_ns, sip))])
    rig.connect()
    rig.responder.x_counts = 250
    rig.run(1.0)
    assert len(seen) == rig.driver.counters().sips > 5  # the failing observer stopped nothing
    last_ns, last = seen[-1]
    assert last_ns == rig.driver.status().last_sip_ns and last.x_counts == 250
    assert [r.message for r in caplog.records if "SIP observer" in r.message] == [
        "pioneer: a SIP observer failed; further failures are not logged"]
