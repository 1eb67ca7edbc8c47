"""The ground-heartbeat failsafe, through the endpoint over real UDP and on its own."""

from __future__ import annotations

from pathlib import Path

import pytest

from robot.vehicle.failsafe import GcsWatchdog, gcs_lost_action
from shared.clock import ManualClock
from shared.link_security import INSECURE_NOTICE
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.mavlink.params.gcs import ParamSetDone
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, make_vehicle

S = 1_000_000_000


def lose_ground(net: Net, app: FakeApp) -> int:
    """Stop the ground's heartbeats; run until the vehicle reports the loss. Returns the
    virtual time from the last heartbeat sent to the loss, ns."""
    net.ground.heartbeat = False
    last_ns = net.ground.last_heartbeat_ns
    assert last_ns is not None
    count = len(app.called("gcs_lost"))
    net.run(lambda: len(app.called("gcs_lost")) > count, max_s=10)
    return net.now_ns - last_ns


def start_mission(net: Net) -> None:
    net.ground.send(*net.ground.mission.upload((Goal(1).to_item(),), net.now_ns))
    net.until_event(net.ground.mission)
    assert net.command(mavlink.MAV_CMD_MISSION_START, 0, 0).result == mavlink.MAV_RESULT_ACCEPTED


def test_manual_stops_reports_and_recovers(net: Net, app: FakeApp) -> None:
    net.advance(2.5)  # ground heartbeats at 0, 1, 2 s
    assert lose_ground(net, app) == 5 * S  # gcs_timeout_ns after the beat at 2 s
    assert app.called("gcs_lost") == [("stop",)]
    net.advance(0.1)
    (notice,) = net.ground.of_type("STATUSTEXT")
    assert notice.severity == mavlink.MAV_SEVERITY_CRITICAL
    assert notice.text == "GCS heartbeat lost for 5.0 s in MANUAL: stop"
    net.advance(1.0)
    assert net.ground.of_type("HEARTBEAT")[-1].system_status == mavlink.MAV_STATE_CRITICAL

    net.ground.heartbeat = True
    net.run(lambda: bool(app.called("gcs_regained")))
    net.advance(1.0)
    assert net.ground.notices()[-1] == "GCS heartbeat regained"
    assert net.ground.of_type("HEARTBEAT")[-1].system_status == mavlink.MAV_STATE_STANDBY
    assert app.called("gcs_lost") == [("stop",)]  # once per loss


def test_auto_holds_by_default(net: Net, app: FakeApp) -> None:
    start_mission(net)
    lose_ground(net, app)
    assert app.called("gcs_lost") == [("hold",)]
    net.advance(0.1)
    assert net.ground.notices()[-1].endswith("in AUTO: hold")


def test_auto_continues_when_the_parameter_says_so(net: Net, app: FakeApp) -> None:
    net.ground.send(*net.ground.params.set("FS_GCS_ACTION", 1, net.now_ns))
    assert net.until_event(net.ground.params) == ParamSetDone("FS_GCS_ACTION", 1, 1, True)
    assert app.configs[-1].mavlink.gcs_lost_action == "continue"
    start_mission(net)
    lose_ground(net, app)
    assert app.called("gcs_lost") == [("continue",)]
    assert app.state.mode is Mode.AUTO


def test_no_failsafe_before_any_ground_heartbeat(net: Net, app: FakeApp) -> None:
    net.ground.heartbeat = False
    net.ground.send(mavlink.MAVLink_param_request_read_message(1, 1, b"CTL_SPEED", -1))
    net.advance(20.0)
    assert net.ground.of_type("PARAM_VALUE")  # the vehicle heard the ground
    assert app.called("gcs_lost") == []


def test_other_vehicles_heartbeats_do_not_count(net: Net, app: FakeApp) -> None:
    net.advance(1.5)
    net.ground.heartbeat = False
    rover = mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GROUND_ROVER,
                                              mavlink.MAV_AUTOPILOT_GENERIC, 1, 0, 3, 3)
    for _ in range(8):
        net.ground.send(rover)
        net.advance(1.0)
    assert app.called("gcs_lost") == [("stop",)]


def test_a_failsafe_clock_times_the_silence(tmp_path: Path, app: FakeApp,
                                            manual_clock: ManualClock) -> None:
    """A lock-step robot's failsafe times the silence on the link's clock and in
    simulated time: 10 s of the link's clock while the simulation stands still (its
    process starved) is no loss, nor 6 s of simulated time in 0.1 s of the link's (a
    simulation faster than real time); both past 5 s is."""
    simulated = ManualClock()
    vehicle = make_vehicle(tmp_path, app, manual_clock, failsafe_clock=simulated)
    net = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    try:
        net.advance(1.5)  # heartbeats at 0 and 1 s of the link's clock, simulated 0
        net.ground.heartbeat = False
        net.advance(10.0)
        assert app.called("gcs_lost") == []
        simulated.advance(4.9)
        net.advance(0.1)
        assert app.called("gcs_lost") == []
        simulated.advance(0.2)
        net.advance(0.1)
        assert app.called("gcs_lost") == [("stop",)]
        net.ground.heartbeat = True
        net.run(lambda: bool(app.called("gcs_regained")))
        net.ground.heartbeat = False  # the simulation races on, the wall clock does not
        simulated.advance(6.0)
        net.advance(0.1)
        assert app.called("gcs_lost") == [("stop",)]
    finally:
        net.close()


class TestWatchdog:
    def test_arms_on_the_first_heartbeat_and_fires_once(self) -> None:
        watchdog = GcsWatchdog(timeout_ns=3 * S)
        assert watchdog.get_timer() is None and watchdog.check(100 * S) is None
        assert watchdog.heartbeat(10 * S) is False
        assert watchdog.get_timer() == 13 * S
        assert watchdog.check(12 * S) is None
        assert watchdog.check(14 * S) == 4 * S and watchdog.lost
        assert watchdog.check(20 * S) is None and watchdog.get_timer() is None
        assert watchdog.heartbeat(21 * S) is True and not watchdog.lost

    def test_on_two_clocks_silence_on_both_is_a_loss(self) -> None:
        watchdog = GcsWatchdog(timeout_ns=3 * S)
        watchdog.heartbeat(10 * S, 100 * S)  # (link, simulation)
        assert watchdog.check(30 * S, 101 * S) is None  # the simulation stood still
        assert watchdog.heartbeat(31 * S, 101 * S) is False
        assert watchdog.check(32 * S, 200 * S) is None  # the simulation raced on
        assert watchdog.check(34 * S, 205 * S) == 3 * S and watchdog.lost  # the shorter

    @pytest.mark.parametrize(("mode", "configured", "action"), [
        (Mode.MANUAL, "continue", "stop"), (Mode.MANUAL, "hold", "stop"),
        (Mode.AUTO, "hold", "hold"), (Mode.AUTO, "continue", "continue"),
        (Mode.GUIDED, "continue", "continue"), (Mode.HOLD, "hold", "hold"),
    ])
    def test_action_by_mode(self, mode: Mode, configured: str, action: str) -> None:
        assert gcs_lost_action(mode, configured) == action


def test_an_insecure_link_warns_each_ground_station_that_connects(
        tmp_path: Path, app: FakeApp, manual_clock: ManualClock) -> None:
    vehicle = make_vehicle(tmp_path, app, manual_clock, link_warning=INSECURE_NOTICE)
    net = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    try:
        net.advance(3.5)  # heartbeats at 0, 1, 2, 3 s: one warning, at connect
        warnings = [m for m in net.ground.of_type("STATUSTEXT")
                    if m.severity == mavlink.MAV_SEVERITY_WARNING]
        assert net.ground.notices() == [INSECURE_NOTICE] and len(warnings) == 1
        lose_ground(net, app)
        net.ground.heartbeat = True
        net.run(lambda: bool(app.called("gcs_regained")))
        net.advance(2.0)
        assert net.ground.notices()[-2:] == ["GCS heartbeat regained", INSECURE_NOTICE]
        assert net.ground.notices().count(INSECURE_NOTICE) == 2
    finally:
        net.close()
