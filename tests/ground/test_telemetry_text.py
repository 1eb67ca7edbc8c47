"""Texts for people (status lines and telemetry lines run in test_ground_cmd.py)."""

from __future__ import annotations

from ground.telemetry_text import not_reached_text


def test_not_reached_says_why_with_the_last_notice() -> None:
    assert not_reached_text(None, 0.5, []) == "still on the way after 0.5 s"
    assert not_reached_text(False, 600.0, ["a", "mission aborted: bumper"]) == (
        "the run stopped short (last notice: mission aborted: bumper)")
