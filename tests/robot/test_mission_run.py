"""MissionRun against fake interfaces: bad goals, failed localization, safety, the camera ending.

The lock-step end-to-end run (teach in the simulator, repeat from an offset) is in
tests/tools/test_demo.py, which drives MissionRun on the simulator's adapters.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.config import FeatureConfig, MissionConfig, VmnavConfig
from robot.mission import MissionState
from robot.mission_run import MissionRun
from robot.vision.features import pixels_per_radian
from shared.clock import ManualClock
from shared.errors import UnknownKeyframeError
from shared.interfaces import BaseState
from tests.shared.memory.builders import PATCH_LENGTH, loop_memory, shared_stretch_memory

PERIOD_NS = 100_000_000


class FakeFrames:
    """Random-noise frames (nothing localizes), optionally ending after ``count``."""

    def __init__(self, shape: tuple[int, int], clock: ManualClock, count: int | None = None):
        self._rng = np.random.default_rng(0)
        self._shape, self._clock, self._left = shape, clock, count

    def read(self):
        if self._left is not None:
            if self._left == 0:
                return None
            self._left -= 1
        return self._clock.now_ns(), self._rng.integers(0, 256, self._shape, dtype=np.uint8)


class FakeBase:
    def __init__(self, bumped: bool = False) -> None:
        self.commands: list[tuple[float, float]] = []
        self.bumped = bumped

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        self.commands.append((v_m_s, omega_rad_s))

    def stop(self) -> None:
        self.commands.append((0.0, 0.0))

    def state(self) -> BaseState:
        return BaseState((0.0, 0.0, 0.0), 0.0, self.bumped, False, 12.5, True)


@pytest.fixture
def memory():
    return loop_memory(np.random.default_rng(5))


class App:
    """A MissionRun with its frames and clock, run like ``MissionRun.run``."""

    def __init__(self, run: MissionRun, frames: FakeFrames, clock: ManualClock) -> None:
        self.mission, self.frames, self.clock = run, frames, clock

    def run(self, goal_id: int, max_duration_ns: int, observer=None):
        return self.mission.run(goal_id, self.frames, self.clock, PERIOD_NS, max_duration_ns,
                                observer)


def make_app(memory, base: FakeBase, count: int | None = None) -> tuple[App, ManualClock]:
    clock = ManualClock()
    # Patches of the memory's side on its lens.
    patch_deg = math.degrees(PATCH_LENGTH**0.5 / pixels_per_radian(memory.camera))
    config = VmnavConfig(features=FeatureConfig(method="harris-zncc", patch_size_deg=patch_deg),
                         mission=MissionConfig(localize_attempts=3))
    frames = FakeFrames((memory.camera.height, memory.camera.width), clock, count)
    return App(MissionRun(memory, config, base, np.random.default_rng(0)), frames, clock), clock


def test_a_goal_not_in_memory_is_refused_before_moving(memory) -> None:
    base = FakeBase()
    app, _ = make_app(memory, base)
    with pytest.raises(UnknownKeyframeError, match="99"):
        app.run(99, 10**10)
    assert base.commands == []


def test_failed_localization_gives_up_stopped_with_events(memory) -> None:
    base = FakeBase()
    app, clock = make_app(memory, base)
    records = []
    result = app.run(5, 10**11, records.append)
    assert result.state is MissionState.FAILED and not result.reached_goal
    assert result.reason == "localization_failed" and "3 failed attempts" in result.detail
    assert [r.state for r in records] == [MissionState.LOCALIZING] * 2 + [MissionState.FAILED]
    assert all(c == (0.0, 0.0) for c in base.commands) and base.commands
    kinds = [(e.kind, e.reason) for e in result.events]
    assert kinds == [("transition", "start")] + [("localization", "failed")] * 3 + [
        ("transition", "localization_failed")]
    assert clock.now_ns() == 3 * PERIOD_NS


def test_a_pressed_bumper_aborts(memory) -> None:
    base = FakeBase(bumped=True)
    app, _ = make_app(memory, base)
    result = app.run(5, 10**11)
    assert result.state is MissionState.ABORTED and result.reason == "bumper"
    assert base.commands[-1] == (0.0, 0.0)


def test_the_camera_ending_aborts(memory) -> None:
    app, _ = make_app(memory, FakeBase(), count=1)
    result = app.run(5, 10**11)
    assert result.state is MissionState.ABORTED and result.detail.endswith("the camera ended")


def test_the_time_limit_aborts(memory) -> None:
    app, _ = make_app(memory, FakeBase())
    result = app.run(5, PERIOD_NS)
    assert result.state is MissionState.ABORTED and "time limit" in result.detail


def test_the_route_starts_at_the_first_key_image_ahead_of_the_view(memory, monkeypatch) -> None:
    from robot.memory.localize import Localization

    base = FakeBase()
    app, _ = make_app(memory, base, count=2)
    # Localized nearest key image 2, with 3 the first one ahead of the robot.
    monkeypatch.setattr(app.mission._localizer, "localize",
                        lambda image, each_path: Localization(2, 40, 30, True, (), 100,
                                                              ahead_id=3))
    result = app.run(5, 10**11)
    localized = [e.detail for e in result.events if e.reason == "localized"]
    assert localized and localized[0].endswith("at key image 3 (40 matches)")
    assert app.mission._route[0] == 3


def test_localized_at_the_goal_just_past_it_has_arrived(memory, monkeypatch) -> None:
    from robot.memory.localize import Localization

    base = FakeBase()
    app, _ = make_app(memory, base, count=2)
    # Nearest key image 5, the goal, with 6 the first one ahead: no route leads back to 5.
    monkeypatch.setattr(app.mission._localizer, "localize",
                        lambda image, each_path: Localization(5, 40, 30, True, (), 100,
                                                              ahead_id=6))
    result = app.run(5, 10**11)
    assert result.state is MissionState.ARRIVED and result.reached_goal
    assert all(command == (0.0, 0.0) for command in base.commands)


def stretch_app(monkeypatch, elsewhere: tuple[tuple[int, int], ...],
                count: int | None = None) -> App:
    """A run on :func:`shared_stretch_memory` whose every localization is the corridor's key
    image 6 (7 the first ahead), and ``elsewhere`` on the loop."""
    from robot.memory.localize import Localization

    app, _ = make_app(shared_stretch_memory(np.random.default_rng(3)), FakeBase(), count)
    monkeypatch.setattr(app.mission._localizer, "localize",
                        lambda image, each_path: Localization(
                            6, 40, 30, True, (), 100, ahead_id=7, elsewhere=elsewhere))
    return app


def test_the_route_starts_on_another_path_at_the_same_place_when_shorter(monkeypatch) -> None:
    # The loop's 17 (ahead: 18) is 2 m past the junction, as the corridor's 6 is. The goal,
    # the loop's end, is out of the corridor's reach.
    app = stretch_app(monkeypatch, ((17, 18),), count=2)
    result = app.run(21, 10**11)
    assert app.mission._route == (18, 19, 20, 21)
    same = [e.detail for e in result.events if e.reason == "same_place"]
    assert same == ["key image 18 (path 1) is where key image 7 is, and the route from it "
                    "is shorter"]


def test_a_look_alike_on_another_path_is_no_start(monkeypatch) -> None:
    # The loop's 14 looks like the corridor's 6, but stands 1.5 m nearer their junction.
    result = stretch_app(monkeypatch, ((14, 15),), count=2).run(21, 10**11)
    assert result.state is MissionState.FAILED and result.reason == "no_route"
    assert "no route from key image 7 to goal key image 21" in result.detail


def test_lost_a_look_alike_far_from_where_the_robot_was_lost_is_refused(monkeypatch) -> None:
    from robot.memory.localize import Localization

    app, _ = make_app(shared_stretch_memory(np.random.default_rng(3)), FakeBase())
    answers = iter([Localization(6, 40, 30, True, (), 100, ahead_id=7)])
    # Then, lost heading for 7, the corridor's start 3.5 m back, again and again.
    monkeypatch.setattr(app.mission._localizer, "localize",
                        lambda image, each_path: next(answers, Localization(
                            0, 40, 30, True, (), 100, ahead_id=0)))
    result = app.run(12, 10**11)
    refused = [e.detail for e in result.events if e.reason == "too_far"]
    assert len(refused) == MissionConfig().relocalize_attempts
    assert refused[0].endswith("more than 2.5 m from key image 7, where the robot was lost")
    assert result.state is MissionState.FAILED and "too_far" not in result.reason
    assert [e.reason for e in result.events].count("relocalized") == 0
