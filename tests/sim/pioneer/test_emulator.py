"""The emulated Pioneer driven by a host-role AriaSession over an in-memory pipe, in lock-step."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from shared.aria import (
    ClientCommand,
    Command,
    ConnState,
    RobotIdentity,
    Sip,
    SipFlags,
    SyncReply,
    encode_packet,
    position_delta,
    vel2,
)
from shared.aria.p3at import ANGLE_CONV_RAD, DIST_CONV_M
from shared.config import AriaLinkConfig
from shared.errors import ConfigError
from sim.config import EmulatorConfig
from tests.sim.pioneer.rig import OPEN_STATES, Rig

SIP_PERIOD_NS = 100_000_000


def odometry_travel(sips: list[tuple[int, Sip]]) -> tuple[float, float, float]:
    """(x_m, y_m, heading change rad) between the first and last SIP, unwrapping counters."""
    x = y = th = 0
    for (_, a), (_, b) in itertools.pairwise(sips):
        x += position_delta(a.x_counts, b.x_counts)
        y += position_delta(a.y_counts, b.y_counts)
        th += (b.th_counts - a.th_counts + 2048) % 4096 - 2048
    return x * DIST_CONV_M, y * DIST_CONV_M, th * ANGLE_CONV_RAD


def last_sip(rig: Rig) -> Sip:
    return rig.host.sips[-1][1]


def truth_speed(rig: Rig) -> float:
    vx, vy, _ = rig.sim.body.velocity_base
    return math.hypot(vx, vy)


@pytest.fixture
def rig() -> Rig:
    return Rig()


@pytest.fixture
def driving(rig: Rig) -> Rig:
    """Connected, motors on, VEL 300 mm/s for 1 s."""
    rig.connect()
    rig.command(Command.ENABLE, 1)
    rig.command(Command.VEL, 300)
    rig.run_for(1.0)
    assert truth_speed(rig) > 0.25
    return rig


class TestHandshake:
    def test_sync_echoes_then_identity_then_sips_after_open(self, rig: Rig) -> None:
        rig.host_end.write(b"WMS2\r")  # ARIA's serial wake-up string comes first
        rig.connect()
        events = rig.host.events
        assert events[:3] == [SyncReply(0), SyncReply(1), RobotIdentity("vmnav", "Pioneer",
                                                                        "p3at-sh")]
        rig.run_for(0.2)
        assert rig.host.sips and rig.host.sips[0][1].sip_type == 0x32
        assert rig.emulator.stats.skipped_bytes == 5

    def test_no_sip_before_open(self, rig: Rig) -> None:
        host = rig.new_host(open_on_identity=False)
        host.connect(rig.now_ns)
        rig.run_for(3.0)
        assert host.session.state is ConnState.CONNECTED
        assert host.sips == [] and rig.emulator.stats.sips_sent == 0
        rig.command(Command.OPEN, 1)
        rig.run_for(0.05)
        assert len(host.sips) == 1

    def test_sips_every_100_ms_from_open(self, rig: Rig) -> None:
        rig.connect()
        rig.run_for(2.0)
        times = [t for t, _ in rig.host.sips]
        assert len(times) >= 20
        assert {b - a for a, b in itertools.pairwise(times)} == {SIP_PERIOD_NS}

    def test_config_reply_has_non_zero_maxima(self, rig: Rig) -> None:
        rig.connect()
        rig.run_for(0.1)
        (config,) = rig.host.configs
        assert config.subclass == "p3at-sh" and config.name == "vmnav"
        assert config.trans_vel_max_m_s > 0 and config.rot_vel_max_rad_s > 0
        assert config.trans_vel_top_m_s >= config.trans_vel_max_m_s
        assert config.sip_cycle_ns == SIP_PERIOD_NS and config.watchdog_ns == 2_000_000_000
        assert config.trans_accel_m_s2 > 0 and config.trans_decel_m_s2 > 0

    def test_config_reflects_setv(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.SETV, 250)
        rig.command(Command.CONFIG, 1)
        rig.run_for(0.1)
        assert rig.host.configs[-1].trans_vel_max_m_s == pytest.approx(0.25)

    def test_link_timing_that_does_not_fit_config_is_refused(self) -> None:
        config = EmulatorConfig(link=AriaLinkConfig(sip_period_ns=300_000_000))
        with pytest.raises(ConfigError, match="sip_cycle"):
            Rig(config=config)


class TestMotion:
    def test_vel_rvel_for_2_s_shows_in_sip_odometry(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 200)
        rig.command(Command.RVEL, 10)
        start = len(rig.host.sips) - 1  # the last SIP before the commands took effect
        rig.run_for(2.0)
        sips = rig.host.sips[start:]
        assert len(sips) >= 20
        x, y, th = odometry_travel(sips)
        distance = math.hypot(x, y)
        assert 0.75 * 0.4 <= distance <= 1.25 * 0.4
        assert 0.75 * math.radians(20) <= th <= 1.25 * math.radians(20)
        assert last_sip(rig).motors_enabled
        assert last_sip(rig).rot_vel_rad_s == pytest.approx(math.radians(10), abs=0.01)
        left, right = last_sip(rig).left_vel_m_s, last_sip(rig).right_vel_m_s
        assert (left + right) / 2 == pytest.approx(0.2, abs=0.01) and right > left

    def test_positions_are_wheel_odometry_not_truth(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.run_for(3.0)
        sip = rig.run_until_sip()
        x_odom = rig.sim.body.odom_pose[0]
        assert sip.x_counts == round(x_odom / DIST_CONV_M) & 0x7FFF
        x_true = rig.sim.body.pose_w[0] - rig.sim.world.start.x_m
        assert abs(x_odom - x_true) > 1e-4  # the seed's scale error makes them differ

    def test_motion_needs_enable(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.VEL, 300)
        rig.run_for(1.0)
        assert truth_speed(rig) < 1e-6 and not last_sip(rig).motors_enabled

    def test_vel_zero_stops(self, driving: Rig) -> None:
        driving.command(Command.VEL, 0)
        driving.command(Command.RVEL, 0)
        driving.run_for(1.0)
        assert truth_speed(driving) < 1e-3
        assert last_sip(driving).left_vel_m_s == last_sip(driving).right_vel_m_s == 0

    def test_setv_limits_speed(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.SETV, 100)
        rig.command(Command.VEL, 400)
        rig.run_for(2.0)
        assert truth_speed(rig) == pytest.approx(0.1, abs=0.005)

    def test_vel2_drives_the_wheels(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.host.send(vel2(0.1, 0.3, 0.02), rig.now_ns)
        rig.run_for(2.0)
        sip = last_sip(rig)
        assert sip.left_vel_m_s == pytest.approx(0.1, abs=0.02)  # odometry's scale errors
        assert sip.right_vel_m_s == pytest.approx(0.3, abs=0.02)

    def test_head_turns_to_a_heading_and_holds(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.HEAD, -90)
        rig.run_for(6.0)
        heading = last_sip(rig).th_counts * ANGLE_CONV_RAD
        assert heading == pytest.approx(-math.pi / 2, abs=math.radians(2))
        assert last_sip(rig).control_counts * ANGLE_CONV_RAD == pytest.approx(-math.pi / 2,
                                                                              abs=0.01)
        assert abs(rig.sim.body.velocity_base[2]) < 0.01

    def test_move_travels_a_distance_and_stops(self, rig: Rig) -> None:
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.MOVE, 500)
        rig.run_for(5.0)
        assert last_sip(rig).x_counts * DIST_CONV_M == pytest.approx(0.5, abs=0.01)
        assert truth_speed(rig) < 1e-3

    def test_seto_resets_odometry(self, driving: Rig) -> None:
        assert last_sip(driving).x_counts > 100
        driving.command(Command.VEL, 0)
        driving.run_for(1.0)
        driving.command(Command.SETO)
        driving.run_for(0.2)
        assert last_sip(driving).x_counts == 0 and last_sip(driving).th_counts == 0

    def test_battery_drains_with_motion(self, rig: Rig) -> None:
        config = EmulatorConfig(battery_drain_v_per_m=0.1)
        rig = Rig(config=config)
        rig.connect()
        rig.run_for(1.0)
        assert last_sip(rig).battery_v == 13.0 == last_sip(rig).real_battery_v
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 500)
        rig.run_for(4.0)
        drained = 13.0 - last_sip(rig).battery_v
        assert drained == pytest.approx(0.1 * rig.sim.body.odom_distance_m, abs=0.06)
        assert drained > 0.1


class TestStops:
    def test_watchdog_stops_after_2_s_silence_and_resumes(self, driving: Rig) -> None:
        driving.host.keepalive = False
        driving.run_for(1.9)
        assert truth_speed(driving) > 0.25
        driving.run_for(1.0)
        assert truth_speed(driving) < 1e-3
        assert driving.emulator.stats.watchdog_trips == 1
        sips_while_silent = len(driving.host.sips)
        driving.run_for(0.5)
        assert len(driving.host.sips) == sips_while_silent + 5  # SIPs keep coming
        driving.command(Command.PULSE)
        driving.run_for(1.0)
        assert truth_speed(driving) > 0.25  # the last motion resumes

    def test_watchdog_only_counts_when_configured_so(self) -> None:
        rig = Rig(config=EmulatorConfig(watchdog_stops=False))
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.host.keepalive = False
        rig.run_for(3.0)
        assert rig.emulator.stats.watchdog_trips == 1 and truth_speed(rig) > 0.25

    def test_e_stop_stops_and_ignores_motion_until_enabled(self, driving: Rig) -> None:
        driving.command(Command.E_STOP, 1)
        driving.run_for(0.6)
        assert truth_speed(driving) < 1e-3
        assert not last_sip(driving).motors_enabled
        driving.command(Command.VEL, 300)
        driving.run_for(1.0)
        assert truth_speed(driving) < 1e-3
        driving.command(Command.ENABLE, 1)
        driving.command(Command.VEL, 300)
        driving.run_for(1.5)
        assert truth_speed(driving) > 0.25

    def test_stop_button(self, driving: Rig) -> None:
        driving.emulator.press_stop_button(True)
        driving.run_for(0.8)
        sip = last_sip(driving)
        assert SipFlags.ESTOP_PRESSED in sip.flags and not sip.motors_enabled
        assert truth_speed(driving) < 1e-3
        driving.command(Command.ENABLE, 1)  # refused while pressed
        driving.command(Command.VEL, 300)
        driving.run_for(0.5)
        assert not last_sip(driving).motors_enabled and truth_speed(driving) < 1e-3
        driving.emulator.press_stop_button(False)
        driving.run_for(0.2)
        assert SipFlags.ESTOP_PRESSED not in last_sip(driving).flags
        assert not last_sip(driving).motors_enabled  # released: still off until ENABLE
        driving.command(Command.ENABLE, 1)
        driving.command(Command.VEL, 300)
        driving.run_for(1.5)
        assert last_sip(driving).motors_enabled and truth_speed(driving) > 0.25

    def test_stop_command_keeps_motors_on(self, driving: Rig) -> None:
        driving.command(Command.STOP)
        driving.run_for(1.0)
        assert truth_speed(driving) < 1e-3 and last_sip(driving).motors_enabled

    def test_close_stops_and_waits_for_sync0(self, driving: Rig) -> None:
        driving.command(Command.CLOSE, 1)
        driving.run_for(0.3)
        assert driving.emulator.state is ConnState.CLOSED
        sips = len(driving.host.sips)
        driving.run_for(1.0)
        assert len(driving.host.sips) == sips and truth_speed(driving) < 1e-3
        driving.new_host()
        driving.connect()
        driving.run_for(0.2)
        assert not last_sip(driving).motors_enabled


class TestReconnection:
    def test_stale_session_new_client_recovers_and_robot_had_stopped(self, driving: Rig) -> None:
        driving.host.keepalive = False  # client A dies mid-motion, its session still open
        driving.run_for(0.5)
        b = driving.new_host()
        driving.connect(timeout_s=2.0)
        assert b.stale_closes == 1  # B saw 0x32 SIPs, sent CLOSE, then re-synced
        assert driving.emulator.stats.watchdog_trips == 0  # B's SYNC0 kept the watchdog fed
        driving.run_for(0.8)
        first = b.sips[0][1]
        assert not first.motors_enabled
        assert truth_speed(driving) < 1e-3 and last_sip(driving).left_vel_m_s == 0
        b.command(Command.ENABLE, 1, driving.now_ns)
        b.command(Command.VEL, 200, driving.now_ns)
        driving.run_for(1.5)
        assert truth_speed(driving) == pytest.approx(0.2, abs=0.01)

    def test_client_that_never_opens_then_a_good_one(self, rig: Rig) -> None:
        silent = rig.new_host(open_on_identity=False)
        silent.connect(rig.now_ns)
        rig.run_for(5.0)
        assert rig.emulator.stats.sips_sent == 0
        rig.new_host()
        rig.connect()
        rig.run_for(0.3)
        assert rig.host.sips

    def test_reset_session_stops_the_robot(self, driving: Rig) -> None:
        driving.host.keepalive = False  # its PULSE would start the new session's handshake
        driving.run_for(0.6)
        driving.emulator.reset_session()
        driving.run_for(1.0)
        assert truth_speed(driving) < 1e-3
        assert driving.emulator.state is ConnState.WAIT_SYNC0
        assert driving.emulator.stats.sessions == 2


class TestBadInput:
    def test_garbage_is_counted_and_the_link_still_works(self, rig: Rig) -> None:
        rng = np.random.default_rng(5)
        vel = ClientCommand(Command.VEL, 200).to_packet().to_bytes()
        junk = [
            rng.integers(0, 256, 3000, dtype=np.uint8).tobytes(),  # random bytes
            vel[:5],  # a truncated packet, then silence past the frame timeout
            b"\xfa\xfb\xff\x0b\x3b",  # COUNT 255, far longer than what follows
            vel[:-1] + bytes((vel[-1] ^ 0xFF,)),  # bad checksum
            encode_packet(14),  # ID 14 is no command
            encode_packet(200, b"\x3b\x01\x00"),  # nor is 200
        ]
        for chunk in junk:
            rig.host_end.write(chunk)
            rig.run_for(0.3)
        stats = rig.emulator.stats
        assert stats.skipped_bytes > 2000
        assert stats.abandoned_frames >= 2
        assert stats.bad_checksums >= 1
        assert stats.unknown_commands >= 2
        rig.connect()
        rig.run_for(0.3)
        assert rig.host.sips

    def test_unknown_and_unemulated_commands_while_open_are_ignored(self, rig: Rig) -> None:
        rig.connect()
        before = rig.emulator.stats
        rig.host_end.write(encode_packet(253) + encode_packet(255) + encode_packet(99))
        rig.command(Command.BATTERYINFO, 1)
        rig.command(Command.HOSTBAUD, 2)
        rig.command(Command.VEL, None)  # a VEL without its argument
        rig.run_for(0.5)
        after = rig.emulator.stats
        assert after.unknown_commands - before.unknown_commands == 1
        assert after.ignored_commands - before.ignored_commands == 5
        assert rig.host.session.state in OPEN_STATES
        assert len(rig.host.sips) >= 5

    def test_commands_before_open_are_ignored(self, rig: Rig) -> None:
        host = rig.new_host(open_on_identity=False)
        host.connect(rig.now_ns)
        rig.run_for(0.2)
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.run_for(1.0)
        assert rig.emulator.stats.ignored_commands == 2 and truth_speed(rig) < 1e-6
