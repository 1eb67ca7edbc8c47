"""``vmnav bench link`` (tools/bench/link.py) and its load generator (tools/bench/link_load.py).

The benchmark runs for real, reduced: 2 vehicles in 2 processes on loopback UDP, a
1 s window, 10 dispatches. The load generator's behaviour as a vehicle application
is checked on a manual clock.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import pytest

from robot.mission import MissionState
from shared.clock import ManualClock
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from tools.bench.link import expected_message_rate
from tools.bench.link_load import KEY_SPACING_M, LOCALIZE_NS, SPEED_M_S, LinkLoadApp, make_load_app
from tools.bench.link_vehicles import AppContext, VehicleProcesses, factory_name, load_factory
from tools.cli import main

STREAMS = {"HEARTBEAT", "SYS_STATUS", "BATTERY_STATUS", "ODOMETRY", "NAV_CONTROLLER_OUTPUT",
           "MISSION_CURRENT", "VISUAL_SERVO_STATUS"}


@pytest.fixture(scope="module")
def result() -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["bench", "link", "--vehicles", "2", "--window-s", "1",
                     "--dispatches", "10"])
    assert code == 0
    return json.loads(out.getvalue())


@pytest.mark.slow
def test_dispatch_times_are_there_and_ordered(result: dict) -> None:
    assert result["benchmark"] == "link" and result["dispatches"] == 10
    p50, p95, top = (result[f"dispatch_ack_ms_{k}"] for k in ("p50", "p95", "max"))
    assert all(isinstance(v, float) and math.isfinite(v) for v in (p50, p95, top))
    assert 0 < p50 <= p95 <= top < 1000


@pytest.mark.slow
def test_the_ground_tracks_every_vehicle_and_measures_its_cpu(result: dict) -> None:
    cpu = result["ground_cpu_fraction_2_vehicles"]
    assert math.isfinite(cpu) and 0 < cpu < 2
    assert result["window_s"] == pytest.approx(1.0, abs=0.2)
    assert result["vehicles_tracked"] == result["vehicles_following_at_end"] == 2
    per_vehicle = result["messages_per_vehicle"]
    assert set(per_vehicle) == {"1", "2"}
    # Every vehicle streamed (nearly) all it should: 14.1 messages/s by default.
    assert result["messages_per_vehicle_expected"] == pytest.approx(14.1, rel=0.2)
    assert min(per_vehicle.values()) == result["messages_per_vehicle_min"]
    assert result["messages_per_vehicle_min"] >= 0.7 * result["messages_per_vehicle_expected"]
    assert set(result["messages_by_type"]) >= STREAMS
    assert sum(result["messages_by_type"].values()) == result["messages_received"]


@pytest.mark.slow
def test_targets_sit_beside_the_figures(result: dict) -> None:
    assert result["targets"] == {"dispatch_ack_ms_p95": "< 50",
                                 "ground_cpu_fraction_20_vehicles": "< 0.3"}
    # Measured with 2 vehicles, the 20-vehicle figure is missing, so not met.
    assert result["targets_met"]["ground_cpu_fraction_20_vehicles"] is False


def test_expected_rate_counts_heartbeat_and_default_streams() -> None:
    # HEARTBEAT 1 + SYS_STATUS, BATTERY_STATUS, MISSION_CURRENT 1 each + ODOMETRY and
    # NAV_CONTROLLER_OUTPUT 4 each + VISUAL_SERVO_STATUS 2 + HOME_POSITION 0.1.
    assert expected_message_rate() == pytest.approx(14.1)


@pytest.mark.parametrize("argv, message", [
    (["--vehicles", "0"], "--vehicles: must be in 1..254"),
    (["--window-s", "0"], "--window-s: must be > 0"),
    (["--dispatches", "0"], "--dispatches: must be >= 1"),
])
def test_bad_sizes_are_one_line_errors(argv: list[str], message: str,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "link", *argv]) == 1
    assert message in capsys.readouterr().err


def broken_factory(context: AppContext) -> LinkLoadApp:
    """An app factory that fails in the vehicles process."""
    raise ValueError(f"no app for vehicle {context.system_id}")


@pytest.mark.slow
def test_a_vehicles_process_that_fails_is_an_error_not_a_hang(
        capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(RuntimeError, match=r"vehicles process \d+ exited with code 1"), \
            VehicleProcesses([1], 1, ground_port=9, key_images=10, app_factory=broken_factory):
        pass
    assert "ValueError: no app for vehicle 1" in capfd.readouterr().err


def test_factories_travel_by_name() -> None:
    assert factory_name(make_load_app) == "tools.bench.link_load:make_load_app"
    assert load_factory("tools.bench.link_load:make_load_app") is make_load_app
    with pytest.raises(ValueError, match="not a module-level function"):
        factory_name(lambda context: make_load_app(context))
    with pytest.raises(ValueError, match="not MODULE:FUNCTION"):
        load_factory("tools.bench.link_load")


# -- the load generator ------------------------------------------------------------------


@pytest.fixture
def app(manual_clock: ManualClock) -> LinkLoadApp:
    return LinkLoadApp(range(10), manual_clock)


def test_it_refuses_goals_outside_its_key_images(app: LinkLoadApp) -> None:
    assert app.validate_goals((Goal(3), Goal(9))) is None
    refusal = app.validate_goals((Goal(3), Goal(10)))
    assert refusal is not None and refusal.result == mavlink.MAV_MISSION_INVALID_PARAM1
    assert "item 1" in refusal.reason


def test_a_mission_localizes_follows_and_arrives(app: LinkLoadApp,
                                                 manual_clock: ManualClock) -> None:
    start = app.telemetry()
    assert (start.mode, start.mission_state, start.servo) == (Mode.HOLD, MissionState.IDLE, None)
    assert app.start_mission((Goal(2), Goal(4)), first_seq=5)
    t = app.telemetry()
    assert (t.mode, t.mission_state, t.mission_seq, t.goal_key) == (
        Mode.AUTO, MissionState.LOCALIZING, 5, 4)
    manual_clock.advance_ns(LOCALIZE_NS)
    manual_clock.advance(1.0)  # 0.2 m along the ring, before key image 1
    t = app.telemetry()
    assert t.mission_state is MissionState.FOLLOWING and t.servo is not None
    assert (t.servo.current_key, t.servo.next_key) == (0, 1)
    assert t.servo.s_m == pytest.approx(0.2 - KEY_SPACING_M)
    assert abs(t.servo.y_m) <= 0.02 and t.servo.matches > 0
    assert t.velocity[0] == SPEED_M_S and math.hypot(*t.odom_pose[:2]) == pytest.approx(
        0.2, abs=0.03)
    manual_clock.advance(2 * KEY_SPACING_M / SPEED_M_S - 1.0)  # past key image 2
    t = app.telemetry()
    assert (t.reached_seqs, t.mission_seq) == ((5,), 6)
    manual_clock.advance(60.0)
    t = app.telemetry()
    assert (t.mode, t.mission_state, t.reached_seqs, t.servo) == (
        Mode.HOLD, MissionState.ARRIVED, (5, 6), None)
    assert "goal key image 4" in t.mission_detail


def test_leaving_auto_aborts_and_disarmed_refuses(app: LinkLoadApp,
                                                  manual_clock: ManualClock) -> None:
    assert app.start_mission((Goal(9),), first_seq=0)
    assert not app.start_mission((Goal(9),), first_seq=0)  # one runs already
    manual_clock.advance(2.0)
    assert app.set_mode(Mode.HOLD)
    t = app.telemetry()
    assert (t.mode, t.mission_state, t.velocity) == (Mode.HOLD, MissionState.ABORTED, (0.0, 0.0))
    assert app.arm(False, force=False)
    assert not app.start_mission((Goal(9),), first_seq=0)
    assert not app.goto_image(Path("x.jpg"))
    assert not app.teach_start("route") and app.next_notice() is None
