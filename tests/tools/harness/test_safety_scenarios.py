"""Issue 17's scenarios in lock-step (tools/harness/safety_scenarios.py), each once."""

from __future__ import annotations

from pathlib import Path

import pytest

from robot.config import VmnavConfig
from tools.harness.safety_scenarios import run_scenario, scenario_config, scenarios

CONFIG = VmnavConfig()
#: The long stand, shortened for the suite: 15 s against a 5 s wait (the benchmark runs the
#: issue's 90 s against the default 60 s).
STAND_S, WAIT_S = 15.0, 5.0


@pytest.mark.parametrize("name", list(scenarios()))
def test_scenario(name: str, east_a: tuple[Path, Path]) -> None:
    scenario = scenarios(stand_s=STAND_S)[name]
    config = scenario_config(CONFIG, WAIT_S if name == "standing_long" else None)
    result = run_scenario(scenario, *east_a, config)
    assert result.passed, result
    assert result.contacts_moving == 0
    if name in ("standing_short", "box"):
        assert result.waits >= 1 and result.resume_latency_s is not None
        assert result.resume_latency_s <= 2.0
    if name == "standing_long":
        assert result.detail.startswith("blocked: blocked for 5.")
        assert result.detail.endswith("s: holding")
    if name == "beside":
        assert result.waits == 0, "a bin beside the corridor stopped the robot"
    if name == "glass_door":
        assert result.detail.startswith("bumper")
