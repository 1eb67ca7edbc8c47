"""Tests of robot/switching.py: key image switching with hysteresis, never skipping."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.config import SwitchingConfig
from robot.switching import (
    SWITCH_REASONS,
    FrameEvidence,
    KeyImageSwitch,
    SwitchState,
    observe_frame,
)

CONFIG = SwitchingConfig()  # 20 px, s >= 0 m, 2 frames


def run(state: SwitchState, frames: list[tuple[float | None, float | None]],
        config: SwitchingConfig = CONFIG) -> tuple[SwitchState, list[KeyImageSwitch | None]]:
    events = []
    for t, (err, s) in enumerate(frames):
        state, event = observe_frame(state, FrameEvidence(t, err, s), config)
        events.append(event)
    return state, events


class TestObserveFrame:
    def test_image_error_after_the_hold(self) -> None:
        state, events = run(SwitchState(route_length=3), [(25.0, -0.3), (19.0, -0.2),
                                                          (18.0, -0.1)])
        assert events[:2] == [None, None]
        assert events[2] == KeyImageSwitch(t_ns=2, reached_index=0, next_index=1,
                                           reason="image_error", err_image_max_px=18.0,
                                           s_m=-0.1, final=False)
        assert state == SwitchState(route_length=3, next_index=1)

    def test_a_small_image_error_far_before_the_key_image_does_not_switch(self) -> None:
        # Distant landmarks: errImageMax is tiny 0.75 m before the key image.
        _, events = run(SwitchState(route_length=3), [(8.0, -0.75), (8.0, -0.7),
                                                      (8.0, -0.24), (8.0, -0.2)])
        assert events[:3] == [None, None, None]
        assert events[3] is not None and events[3].reason == "image_error"
        paper = SwitchingConfig(image_error_within_m=math.inf)
        _, events = run(SwitchState(route_length=3), [(8.0, -0.75), (8.0, -0.7)], paper)
        assert events[1] is not None and events[1].reason == "image_error"

    def test_passed_after_the_hold(self) -> None:
        state, events = run(SwitchState(route_length=3), [(40.0, -0.01), (40.0, 0.0),
                                                          (40.0, 0.02)])
        assert events[2] is not None and events[2].reason == "passed"
        assert state.next_index == 1

    def test_a_failing_frame_resets_the_count(self) -> None:
        _, events = run(SwitchState(route_length=3), [(19.0, None), (21.0, None), (19.0, None),
                                                      (19.0, None)])
        assert events[:3] == [None, None, None] and events[3] is not None

    def test_missing_evidence_keeps_the_count(self) -> None:
        _, events = run(SwitchState(route_length=3), [(None, 0.01), (None, None), (None, 0.02)])
        assert events[:2] == [None, None] and events[2] is not None

    @pytest.mark.parametrize("err", [math.inf, math.nan])
    def test_no_matches_is_evidence_against(self, err: float) -> None:
        _, events = run(SwitchState(route_length=3), [(19.0, None), (err, None), (19.0, None)])
        assert events == [None, None, None]

    def test_image_error_wins_when_both_hold(self) -> None:
        _, events = run(SwitchState(route_length=3), [(10.0, 0.1), (10.0, 0.1)])
        assert events[1] is not None and events[1].reason == "image_error"

    def test_margin(self) -> None:
        config = SwitchingConfig(pass_margin_m=0.05, hold_frames=1)
        _, events = run(SwitchState(route_length=3), [(None, 0.04), (None, 0.05)], config)
        assert events[0] is None and events[1] is not None

    def test_one_key_image_per_frame_when_far_behind(self) -> None:
        # robot far past several key images: every one gets its own switch and event
        state, events = run(SwitchState(route_length=3), [(5.0, 2.0)] * 6)
        assert [e.reached_index if e else None for e in events] == [None, 0, None, 1, None, 2]
        assert events[5].final and state.finished

    def test_finished_takes_no_more_frames(self) -> None:
        state, _ = run(SwitchState(route_length=1), [(5.0, None), (5.0, None)])
        with pytest.raises(RuntimeError, match=r"last key image \(index 0\) was already reached"):
            observe_frame(state, FrameEvidence(9, 5.0, None), CONFIG)

    @given(frames=st.lists(st.tuples(
        st.one_of(st.none(), st.floats(0, 60), st.just(math.inf)),
        st.one_of(st.none(), st.floats(-1, 1))), max_size=60),
        hold=st.integers(1, 4), route_length=st.integers(1, 6))
    def test_never_skips(self, frames: list[tuple[float | None, float | None]], hold: int,
                         route_length: int) -> None:
        config = SwitchingConfig(hold_frames=hold)
        state = SwitchState(route_length=route_length)
        last_switch = -1
        for t, (err, s) in enumerate(frames):
            if state.finished:
                break
            before = state.next_index
            state, event = observe_frame(state, FrameEvidence(t, err, s), config)
            assert state.next_index - before == (0 if event is None else 1)
            if event is not None:
                assert event.reached_index == before and event.reason in SWITCH_REASONS
                assert event.final == (event.next_index == route_length)
                assert t - last_switch >= hold  # hysteresis restarts after each switch
                last_switch = t


class TestSwitchState:
    def test_starts_at_the_first_key_image(self) -> None:
        state = SwitchState(route_length=4)
        assert (state.next_index, state.finished) == (0, False)

    @pytest.mark.parametrize(("length", "index", "message"), [
        (0, 0, "route_length must be >= 1"), (3, 4, r"next_index must be in \[0, 3\]"),
        (3, -1, "next_index must be in"),
    ])
    def test_bad_values(self, length: int, index: int, message: str) -> None:
        with pytest.raises(ValueError, match=message):
            SwitchState(route_length=length, next_index=index)
