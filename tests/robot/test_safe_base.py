"""Tests of robot/safe_base.py: the safety layer in front of a base."""

from __future__ import annotations

import dataclasses

from robot.config import SafetyConfig
from robot.safe_base import SafeBase
from shared.clock import ManualClock
from shared.interfaces import BaseState
from tests.robot.test_safety import echo_ahead, state


class RecordingBase:
    """A base with an E_STOP that records what it was told."""

    def __init__(self, reported: BaseState) -> None:
        self.reported = reported
        self.calls: list[tuple[str, float, float]] = []

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        self.calls.append(("command", v_m_s, omega_rad_s))

    def stop(self) -> None:
        self.calls.append(("stop", 0.0, 0.0))

    def state(self) -> BaseState:
        return self.reported

    def e_stop(self) -> None:
        self.calls.append(("e_stop", 0.0, 0.0))

    def enable_motors(self) -> None:
        self.calls.append(("enable_motors", 0.0, 0.0))


def test_commands_pass_the_governor() -> None:
    base = RecordingBase(state())
    safe = SafeBase(base, ManualClock(), SafetyConfig())
    safe.command(0.2, 0.1)
    base.reported = state(echo_ahead(0.3))
    safe.command(0.2, 0.0)
    assert base.calls == [("command", 0.2, 0.1), ("stop", 0.0, 0.0)]


def test_the_state_carries_the_hold() -> None:
    base = RecordingBase(state(echo_ahead(0.3)))
    safe = SafeBase(base, ManualClock(), SafetyConfig())
    blocked = safe.state().blocked
    assert blocked is not None and blocked.cause == "obstacle"
    assert safe.state().ranges == base.reported.ranges


def test_the_emergency_stop_uses_the_base_e_stop_and_holds_until_released() -> None:
    base = RecordingBase(state())
    safe = SafeBase(base, ManualClock(), SafetyConfig())
    safe.emergency_stop()
    safe.command(0.2, 0.0)
    assert base.calls == [("e_stop", 0.0, 0.0), ("stop", 0.0, 0.0)]
    assert safe.state().blocked.cause == "e_stop"
    safe.release()
    safe.command(0.2, 0.0)
    assert base.calls[2:] == [("enable_motors", 0.0, 0.0), ("command", 0.2, 0.0)]


def test_switched_off_it_passes_commands_but_keeps_the_emergency_stop() -> None:
    base = RecordingBase(state(echo_ahead(0.1)))
    safe = SafeBase(base, ManualClock(), dataclasses.replace(SafetyConfig(), enabled=False))
    safe.command(0.2, 0.0)
    assert safe.state().blocked is None
    safe.emergency_stop()
    safe.command(0.2, 0.0)
    assert base.calls == [("command", 0.2, 0.0), ("e_stop", 0.0, 0.0), ("stop", 0.0, 0.0)]


def test_new_settings_apply_to_the_next_command() -> None:
    base = RecordingBase(state(echo_ahead(0.5)))
    safe = SafeBase(base, ManualClock(), SafetyConfig())
    safe.command(0.2, 0.0)
    safe.configure(SafetyConfig(stop_distance_m=0.6, slow_distance_m=1.5))
    safe.command(0.2, 0.0)
    assert base.calls[0][0] == "command" and base.calls[1] == ("stop", 0.0, 0.0)
