"""Tests of shared/interfaces.py: the application's Protocols and the base state."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest

from shared.clock import ManualClock
from shared.interfaces import BaseState, Clock, FrameSource, MobileBase


def base_state(**changes: object) -> BaseState:
    values: dict[str, object] = dict(odom_pose=(1.0, -0.5, 0.3), odom_distance_m=2.5,
                                     bumped=False, stalled=False, battery_v=12.6,
                                     motors_enabled=True)
    values.update(changes)
    return BaseState(**values)  # type: ignore[arg-type]


class FakeCamera:
    def __init__(self, frames: list[tuple[int, npt.NDArray[np.uint8]]]) -> None:
        self._frames = list(frames)

    def read(self) -> tuple[int, npt.NDArray[np.uint8]] | None:
        return self._frames.pop(0) if self._frames else None


class FakeBase:
    def __init__(self) -> None:
        self.commands: list[tuple[float, float]] = []

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        self.commands.append((v_m_s, omega_rad_s))

    def stop(self) -> None:
        self.command(0.0, 0.0)

    def state(self) -> BaseState:
        return base_state()


class TestBaseState:
    def test_holds_the_values(self) -> None:
        state = base_state()
        assert state.odom_pose == (1.0, -0.5, 0.3) and state.battery_v == 12.6

    @pytest.mark.parametrize(("changes", "message"), [
        ({"odom_pose": (1.0, 2.0)}, "odom_pose must be 3 finite numbers"),
        ({"odom_pose": (1.0, math.nan, 0.0)}, "odom_pose must be 3 finite numbers"),
        ({"odom_distance_m": -0.1}, "odom_distance_m must be finite and >= 0"),
    ])
    def test_bad_values(self, changes: dict[str, object], message: str) -> None:
        with pytest.raises(ValueError, match=message):
            base_state(**changes)


class TestProtocols:
    def test_fakes_satisfy_them(self) -> None:
        camera = FakeCamera([(5, np.zeros((600, 800), np.uint8))])
        assert isinstance(camera, FrameSource)
        assert isinstance(FakeBase(), MobileBase)
        assert not isinstance(camera, MobileBase)

    def test_a_frame_source_ends_with_none(self) -> None:
        camera = FakeCamera([(5, np.zeros((600, 800), np.uint8))])
        t_ns, image = camera.read()
        assert (t_ns, image.shape, image.dtype) == (5, (600, 800), np.uint8)
        assert camera.read() is None

    def test_clock_is_the_shared_one(self) -> None:
        clock: Clock = ManualClock()
        assert clock.now_ns() == 0
