"""RobotProcess: the loop (frames, stalls, the end), holding a lock-step clock while a
ground station answers over loopback UDP, and the closing order.

The loop's clock is a ManualClock moved by a scripted camera; the link runs on the
wall clock (its I/O thread must not move the loop's time).
"""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from robot.camera import Frame, FrameStall
from robot.config import VmnavConfig
from robot.field_log import FieldLog
from robot.process import CAMERA_ENDED, STOPPED, TIME_UP, AfterStep, RobotParts, RobotProcess
from robot.vehicle.options import VehicleFiles
from shared.camera_model import CameraModel
from shared.clock import ManualClock, WallClock
from shared.config import CameraMountConfig, LogConfig
from shared.errors import IllegalEventError, TransportError
from shared.interfaces import BaseState
from shared.logs.reader import read_messages
from shared.logs.writer import LogStats
from shared.mavlink.modes import Mode
from shared.memory import VisualMemory
from shared.pose import Pose2

MS = 1_000_000
#: Unix time at the loop clock's zero (2025-11-14 16:00:00 UTC), ns.
EPOCH_NS = 1_763_136_000_000_000_000
CAMERA = CameraModel.default()


class RecordingBase:
    """A MobileBase that stands still and records what it was told."""

    def __init__(self, calls: list[str]) -> None:
        self.calls = calls

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        self.calls.append(f"command {v_m_s} {omega_rad_s}")

    def stop(self) -> None:
        self.calls.append("stop")

    def state(self) -> BaseState:
        return BaseState(Pose2(0.0, 0.0, 0.0), 0.0, bumped=False, stalled=False, battery_v=12.5,
                         motors_enabled=True)


class ScriptedCamera:
    """Frames at the given times (ns; None: a stall), moving the clock to each, then the end."""

    def __init__(self, clock: ManualClock, times_ns: list[int | None]) -> None:
        self._clock = clock
        self._times = iter(times_ns)
        self.reads = 0

    def read_within(self, timeout_ns: int) -> Frame | FrameStall | None:
        t_ns = next(self._times, -1)
        if t_ns == -1:
            return None
        self.reads += 1
        if t_ns is None:
            self._clock.advance_ns(timeout_ns)
            return FrameStall(self._clock.now_ns(), 0)
        self._clock.sleep_until_ns(t_ns)
        return self._clock.now_ns(), np.zeros((CAMERA.height, CAMERA.width), np.uint8)


class OrderedLog(FieldLog):
    """A field log that says when it is finished."""

    def __init__(self, folder: Path, calls: list[str]) -> None:
        super().__init__(LogConfig(output_dir=str(folder)), "robot", CameraMountConfig(),
                         {"source": "test"}, unix_offset_ns=0)
        self._calls = calls

    def close(self) -> LogStats:
        self._calls.append("log finished")
        return super().close()


def parts(tmp_path: Path, clock: ManualClock, frames: ScriptedCamera, calls: list[str], *,
          log: FieldLog | None = None, lockstep: bool = False) -> RobotParts:
    files = VehicleFiles(tmp_path / "memory", tmp_path / "state" / "upload",
                         tmp_path / "state" / "params.parm")
    return RobotParts(VisualMemory(CAMERA), RecordingBase(calls), frames, clock, VmnavConfig(),
                      files, np.random.default_rng(1), log=log, lockstep=lockstep)


@contextlib.contextmanager
def process(tmp_path: Path, clock: ManualClock, frames: ScriptedCamera, calls: list[str],
            **options) -> Iterator[RobotProcess]:
    with RobotProcess(parts(tmp_path, clock, frames, calls, **options), "udpin:127.0.0.1:0",
                      link_clock=WallClock()) as robot:
        yield robot


def record_notices(robot: RobotProcess) -> list[str]:
    """Every notice the runtime gives from now on, whoever takes it (the link's thread
    sends them as STATUSTEXT whenever it gets a core)."""
    taken: list[str] = []
    give = robot.runtime.next_notice

    def next_notice() -> tuple[int, str] | None:
        notice = give()
        if notice is not None:
            taken.append(notice[1])
        return notice

    robot.runtime.next_notice = next_notice  # type: ignore[method-assign]
    return taken


class TestLoop:
    def test_frames_go_to_the_runtime_and_a_stall_stops_the_base(self, tmp_path) -> None:
        clock, calls, steps = ManualClock(), [], []
        frames = ScriptedCamera(clock, [100 * MS, None, 800 * MS])
        with process(tmp_path, clock, frames, calls) as robot:
            said = record_notices(robot)

            def on_step(record) -> AfterStep:
                steps.append((clock.now_ns(), record))
                return AfterStep.NEXT_FRAME

            assert robot.run(on_step=on_step) == CAMERA_ENDED
            while robot.runtime.next_notice() is not None:
                pass
        assert steps == [(100 * MS, None), (800 * MS, None)]  # HOLD: no mission cycle
        # No frame within TeleopConfig.frame_timeout_ns (0.5 s) of the first: stalled at 0.6 s.
        assert said == ["camera stalled: stopped until frames return", "camera back after 0.2 s"]
        assert set(calls) == {"stop"}

    def test_the_time_given_ends_it(self, tmp_path) -> None:
        clock = ManualClock()
        frames = ScriptedCamera(clock, [100 * MS * k for k in range(1, 100)])
        with process(tmp_path, clock, frames, []) as robot:
            assert robot.run(end_ns=1000 * MS) == TIME_UP
        assert frames.reads == 10 and clock.now_ns() == 1000 * MS

    def test_a_period_paces_it_on_the_clock_and_on_step_stops_it(self, tmp_path) -> None:
        clock, stamps = ManualClock(), []
        frames = ScriptedCamera(clock, [0] * 100)  # a frame whenever asked, at the clock's time

        def on_step(record) -> AfterStep:
            stamps.append(clock.now_ns())
            return AfterStep.STOP if len(stamps) == 4 else AfterStep.NEXT_FRAME

        with process(tmp_path, clock, frames, []) as robot:
            assert robot.run(period_ns=50 * MS, on_step=on_step) == STOPPED
        assert stamps == [0, 50 * MS, 100 * MS, 150 * MS]

    def test_stop_ends_it_before_the_next_frame_with_its_reason(self, tmp_path) -> None:
        clock, stamps = ManualClock(), []
        frames = ScriptedCamera(clock, [0] * 100)
        with process(tmp_path, clock, frames, []) as robot:
            def on_step(record) -> AfterStep:  # as a signal handler would, mid-loop
                stamps.append(clock.now_ns())
                if len(stamps) == 3:
                    robot.stop("stopped by SIGINT")
                return AfterStep.NEXT_FRAME

            assert robot.run(period_ns=50 * MS, on_step=on_step) == "stopped by SIGINT"
        assert stamps == [0, 50 * MS, 100 * MS] and frames.reads == 3


class TestHoldingTheClock:
    def test_the_ground_station_is_heard_while_the_clock_stands_still(self, tmp_path) -> None:
        from ground.station import GroundStation

        clock, calls, stamps = ManualClock(5000 * MS), [], []
        frames = ScriptedCamera(clock, [5000 * MS, 5070 * MS])
        log = FieldLog(LogConfig(output_dir=str(tmp_path / "logs")), "robot",
                       CameraMountConfig(), {"source": "test"}, unix_offset_ns=EPOCH_NS)
        wall = WallClock()
        with process(tmp_path, clock, frames, calls, log=log, lockstep=True) as robot:
            port = robot.vehicle.link.local_port

            def operator() -> None:
                with GroundStation.open(f"udpout:127.0.0.1:{port}", wall) as station:
                    station.wait_vehicle(20.0)
                    station.set_mode(Mode.MANUAL)

            ground = threading.Thread(target=operator, daemon=True)
            give_up_ns = wall.now_ns() + 30_000 * MS

            def on_step(record) -> AfterStep:
                stamps.append(clock.now_ns())
                if robot.runtime.telemetry().mode is Mode.MANUAL or wall.now_ns() > give_up_ns:
                    return AfterStep.STOP
                return AfterStep.HOLD_CLOCK

            ground.start()
            assert robot.run(period_ns=70 * MS, on_step=on_step) == STOPPED
            ground.join(30)
        assert robot.runtime.telemetry().mode is Mode.MANUAL
        assert len(stamps) > 1 and set(stamps) == {5000 * MS}  # the same frame, time held
        # The link's traffic is stamped on the loop's clock, which stood still.
        traffic = list(read_messages(log.stats().files[0], None))
        stamped = {m.clock_ns for m in traffic if m.topic.startswith("/mavlink/")}
        assert stamped == {5000 * MS}
        assert any(m.topic == "/mavlink/in/COMMAND_LONG" for m in traffic)

    def test_rejected_traffic_is_counted_in_the_log_not_logged(self, tmp_path) -> None:
        from robot.vehicle.udp_vehicle import REJECT_REPORT_PERIOD_NS, Rejected
        from shared.udp_link import UdpLink

        clock = ManualClock(7000 * MS)
        log = FieldLog(LogConfig(output_dir=str(tmp_path / "logs")), "robot",
                       CameraMountConfig(), {"source": "test"}, unix_offset_ns=EPOCH_NS)
        wall = WallClock()
        with process(tmp_path, clock, ScriptedCamera(clock, []), [], log=log) as robot:
            # A well-framed packet of an id the dialect lacks: it decodes, unverified.
            unknown = bytes([0xFD, 4, 0, 0, 0, 42, 1, 0xEF, 0xCD, 0xAB]) + bytes(6)
            with UdpLink.open(f"udpout:127.0.0.1:{robot.vehicle.link.local_port}") as stranger:
                for _ in range(3):
                    stranger.send(unknown)
                give_up_ns = wall.now_ns() + 10_000 * MS
                while robot.vehicle.unverified < 3 and wall.now_ns() < give_up_ns:
                    wall.sleep_until_ns(wall.now_ns() + 10 * MS)
            assert robot.vehicle.unverified == 3
            for observe in robot.vehicle.reject_observers:  # as at the end of a period
                observe(Rejected(3, 0, REJECT_REPORT_PERIOD_NS), wall.now_ns())
        messages = list(read_messages(log.stats().files[0], None))
        assert not any(m.topic.startswith("/mavlink/in/") for m in messages)
        [line] = [m for m in messages if m.topic == "/log" and m.data["name"] == "robot.vehicle"]
        assert line.clock_ns == 7000 * MS  # on the loop's clock
        assert line.log_time_ns == EPOCH_NS + 7000 * MS  # in Unix time
        assert line.data["message"] == ("mavlink in: 3 datagrams rejected in 10.0 s (3 without "
                                        "a verified message, 0 shed unparsed)")

    def test_only_a_lockstep_process_holds_its_clock(self, tmp_path) -> None:
        clock = ManualClock()
        with process(tmp_path, clock, ScriptedCamera(clock, [0]), []) as robot, \
                pytest.raises(ValueError, match="lock-step"):
            robot.run(on_step=lambda record: AfterStep.HOLD_CLOCK)


class TestClosing:
    def test_link_runtime_owned_parts_log_end_then_the_log(self, tmp_path) -> None:
        clock, calls = ManualClock(), []
        owned = contextlib.ExitStack()
        owned.callback(calls.append, "camera closed")
        owned.callback(calls.append, "pioneer closed")
        robot = RobotProcess(
            parts(tmp_path, clock, ScriptedCamera(clock, []), calls,
                  log=OrderedLog(tmp_path / "logs", calls)),
            "udpin:127.0.0.1:0", link_clock=WallClock(), owned=owned,
            log_end=lambda log: calls.append(f"log_end {type(log).__name__}"))
        calls.clear()
        robot.close()
        assert calls == ["stop", "pioneer closed", "camera closed", "log_end OrderedLog",
                         "log finished"]
        with pytest.raises(IllegalEventError):
            robot.vehicle.start_thread()  # the link is closed
        robot.close()
        assert calls[-1] == "log finished" and len(calls) == 5

    def test_a_port_in_use_closes_what_was_handed_over(self, tmp_path) -> None:
        clock, calls = ManualClock(), []
        owned = contextlib.ExitStack()
        owned.callback(calls.append, "pioneer closed")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
            taken.bind(("127.0.0.1", 0))
            port = taken.getsockname()[1]
            with pytest.raises(TransportError, match=str(port)):
                RobotProcess(parts(tmp_path, clock, ScriptedCamera(clock, []), calls,
                                   log=OrderedLog(tmp_path / "logs", calls)),
                             f"udpin:127.0.0.1:{port}", owned=owned,
                             log_end=lambda log: calls.append("log_end"))
        assert calls == ["stop", "pioneer closed", "log_end", "log finished"]
