"""Tests of ``vmnav bench safety`` (tools/bench/safety.py): its cheap part through the
command line and its summary (the scenarios have their own tests in
tests/tools/harness/test_safety_scenarios.py, the truth in test_safety_truth.py, the
emergency stop its fault case)."""

from __future__ import annotations

import json

import pytest

from tools.bench.safety import summary
from tools.cli import main


def test_the_governor_part_prints_its_cost(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "safety", "--parts", "governor"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["benchmark"] == "safety" and result["lost_distance_m"] == 1.0
    assert 0 < result["governor"]["ms_p50"] <= result["governor"]["ms_p95"]
    assert 0 < result["governor"]["frame_ms_p50"] <= result["governor"]["frame_ms_p95"]
    assert result["summary"] == {"governor_frame_ms_p95": result["governor"]["frame_ms_p95"]}


@pytest.mark.parametrize(("args", "message"), [
    (["--seeds", "0"], "--seeds: must be >= 1, got 0"),
    (["--people", "-3"], "--people: must be >= 1, got -3"),
    (["--estops", "0"], "--estops: must be >= 1, got 0"),
])
def test_bad_arguments_are_one_line(args: list[str], message: str,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "safety", *args]) == 1
    assert message in capsys.readouterr().err


def test_summary_holds_the_parts_that_ran() -> None:
    people = {"lab": {"seeds": [{}, {}], "reached_with_people": 1, "contacts_moving": 0,
                      "lateral_rms_delta_m_max": 0.004, "blind_m_max": 1.02}}
    result = {"lost_distance_m": 1.0, "scenarios": [{"passed": True}, {"passed": False}],
              "people": people, "governor": {"frame_ms_p95": 0.05}}
    assert summary(result) == {
        "scenarios_failed": 1, "people_contacts_moving": 0, "people_reached_short": 1,
        "people_lateral_rms_delta_m_max": 0.004, "blind_m_over_bound": -0.03,
        "governor_frame_ms_p95": 0.05}
