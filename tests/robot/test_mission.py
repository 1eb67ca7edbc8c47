"""Tests of robot/mission.py: the mission state machine and its transition table."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot import mission as m
from robot.config import MissionConfig, SafetyConfig
from robot.mission import (
    FINAL_STATES,
    REASONS,
    Abort,
    Arrived,
    Bumper,
    Command,
    KeyImageReached,
    LocalizationFailed,
    Localized,
    Lost,
    Mission,
    MissionState,
    NoRoute,
    Obstacle,
    Stall,
    Start,
    Tick,
    Transition,
    WayClear,
)
from shared.clock import ns_from_s
from shared.errors import IllegalEventError, VmnavError

CONFIG = MissionConfig(localize_attempts=3, localize_timeout_ns=ns_from_s(10),
                       relocalize_attempts=2, relocalize_timeout_ns=ns_from_s(5))


def following(at_s: float = 1.0) -> Mission:
    mission = Mission(CONFIG)
    mission.handle(Start(0, goal_id=42))
    mission.handle(Localized(ns_from_s(at_s), keyframe_id=7, matches=120))
    return mission


def lost(at_s: float = 2.0) -> Mission:
    mission = following()
    mission.handle(Lost(ns_from_s(at_s), "no usable vision estimate for 2.00 s"))
    return mission


class TestHandle:
    def test_happy_path(self) -> None:
        mission = Mission(CONFIG)
        assert mission.state is MissionState.IDLE and mission.goal_id is None
        start = mission.handle(Start(0, goal_id=42))
        assert start == Transition(0, MissionState.IDLE, MissionState.LOCALIZING, "start",
                                   "to goal key image 42", Start(0, 42),
                                   (Command.STOP, Command.LOCALIZE))
        assert mission.goal_id == 42
        localized = mission.handle(Localized(5, keyframe_id=7, matches=120))
        assert (localized.target, localized.reason, localized.detail, localized.commands) == (
            MissionState.FOLLOWING, "localized", "at key image 7 (120 matches)",
            (Command.FOLLOW,))
        arrived = mission.handle(Arrived(9, keyframe_id=42))
        assert (arrived.target, arrived.reason, arrived.detail, arrived.commands) == (
            MissionState.ARRIVED, "arrived", "at goal key image 42", (Command.STOP,))

    def test_lost_stops_relocalizes_and_continues(self) -> None:
        mission = following()
        lost_transition = mission.handle(Lost(ns_from_s(2), "3 estimates rejected"))
        assert (lost_transition.target, lost_transition.reason, lost_transition.detail) == (
            MissionState.LOST, "lost", "3 estimates rejected")
        assert lost_transition.commands == (Command.STOP, Command.LOCALIZE)
        back = mission.handle(Localized(ns_from_s(3), keyframe_id=9, matches=80))
        assert (back.source, back.target, back.reason) == (
            MissionState.LOST, MissionState.FOLLOWING, "relocalized")

    def test_localization_gives_up_after_the_attempts(self) -> None:
        mission = Mission(CONFIG)
        mission.handle(Start(0, 42))
        assert mission.handle(LocalizationFailed(1, "12 matches (need 25)")) is None
        assert mission.handle(LocalizationFailed(2, "12 matches (need 25)")) is None
        failed = mission.handle(LocalizationFailed(3, "12 matches (need 25)"))
        assert (failed.target, failed.reason, failed.commands) == (
            MissionState.FAILED, "localization_failed", (Command.STOP,))
        assert failed.detail == "3 failed attempts in a row (limit 3): 12 matches (need 25)"

    def test_localization_times_out_at_the_limit_not_before(self) -> None:
        mission = Mission(CONFIG)
        mission.handle(Start(ns_from_s(1), 42))
        assert mission.handle(Tick(ns_from_s(11) - 1)) is None
        failed = mission.handle(Tick(ns_from_s(11)))
        assert (failed.target, failed.reason, failed.detail) == (
            MissionState.FAILED, "localization_timeout", "localizing for 10.0 s (limit 10.0 s)")

    def test_relocalization_limits_count_from_entering_lost(self) -> None:
        mission = lost(at_s=2.0)
        assert mission.handle(LocalizationFailed(ns_from_s(3), "few matches")) is None
        mission.handle(Localized(ns_from_s(4), 9, 80))
        mission.handle(Lost(ns_from_s(6), "again"))
        assert mission.handle(LocalizationFailed(ns_from_s(7), "few matches")) is None  # 1 of 2
        assert mission.handle(Tick(ns_from_s(11) - 1)) is None
        failed = mission.handle(Tick(ns_from_s(11)))
        assert (failed.target, failed.reason) == (MissionState.FAILED, "relocalization_timeout")

    def test_relocalization_gives_up_after_the_attempts(self) -> None:
        mission = lost()
        mission.handle(LocalizationFailed(ns_from_s(3), "few matches"))
        failed = mission.handle(LocalizationFailed(ns_from_s(4), "few matches"))
        assert (failed.target, failed.reason) == (MissionState.FAILED, "relocalization_failed")

    @pytest.mark.parametrize(("event", "reason", "detail"), [
        (Bumper(ns_from_s(5)), "bumper", "bumper pressed"),
        (Stall(ns_from_s(5)), "stall", "motors stalled"),
        (Abort(ns_from_s(5)), "operator_abort", "operator abort"),
        (Abort(ns_from_s(5), "gcs_lost", "ground heartbeat lost: mode HOLD"), "gcs_lost",
         "ground heartbeat lost: mode HOLD"),
        (Abort(ns_from_s(5), "time_limit", "time limit 60 s reached"), "time_limit",
         "time limit 60 s reached"),
    ])
    @pytest.mark.parametrize("make", [following, lost])
    def test_safety_aborts(self, make: Callable[[], Mission], event: m.MissionInput, reason: str,
                           detail: str) -> None:
        mission = make()
        aborted = mission.handle(event)
        assert (aborted.target, aborted.reason, aborted.detail, aborted.commands) == (
            MissionState.ABORTED, reason, detail, (Command.STOP,))

    def test_safety_while_localizing(self) -> None:
        mission = Mission(CONFIG)
        mission.handle(Start(0, 42))
        assert mission.handle(Bumper(1)).target is MissionState.ABORTED

    @pytest.mark.parametrize("event", [Bumper(1), Stall(1), Abort(1), Tick(1),
                                       Lost(1, "late")])
    def test_ignored_when_idle_or_final(self, event: m.MissionInput) -> None:
        idle = Mission(CONFIG)
        assert idle.handle(event) is None and idle.state is MissionState.IDLE
        done = following(at_s=0.0)
        done.handle(Arrived(1, 42))
        assert done.handle(event) is None and done.state is MissionState.ARRIVED

    @pytest.mark.parametrize(("make", "event", "state"), [
        (lambda: Mission(CONFIG), Localized(1, 7, 99), "IDLE"),
        (lambda: Mission(CONFIG), Arrived(1, 7), "IDLE"),
        (following, Start(ns_from_s(2), 3), "FOLLOWING"),
        (following, Localized(ns_from_s(2), 7, 99), "FOLLOWING"),
        (following, LocalizationFailed(ns_from_s(2), "x"), "FOLLOWING"),
        (lost, Start(ns_from_s(3), 42), "LOST"),
    ])
    def test_illegal_inputs_raise(self, make: Callable[[], Mission], event: m.MissionInput,
                                  state: str) -> None:
        mission = make()
        with pytest.raises(IllegalEventError) as info:
            mission.handle(event)
        name = type(event).__name__
        assert str(info.value) == f"mission: event {name} is not allowed in state {state}"
        assert (info.value.state, info.value.event) == (state, name)
        assert mission.state is MissionState[state]  # unchanged

    def test_time_must_not_go_backwards(self) -> None:
        mission = following(at_s=1.0)
        with pytest.raises(ValueError, match="earlier than the previous input"):
            mission.handle(Tick(ns_from_s(0.5)))


class TestSafetyWait:
    def test_an_obstacle_waits_and_the_way_clearing_resumes(self) -> None:
        mission = following()
        waiting = mission.handle(Obstacle(ns_from_s(3.0), "obstacle 0.45 m ahead"))
        assert (waiting.target, waiting.reason, waiting.detail, waiting.commands) == (
            MissionState.WAITING, "obstacle", "obstacle 0.45 m ahead: waiting", (Command.STOP,))
        assert mission.handle(Lost(ns_from_s(5.0), "late")) is None  # stood still
        resumed = mission.handle(WayClear(ns_from_s(9.2)))
        assert (resumed.target, resumed.reason, resumed.detail) == (
            MissionState.FOLLOWING, "resumed", "way clear after 6.2 s: resuming")

    def test_blocked_for_the_wait_holds(self) -> None:
        mission = Mission(CONFIG, SafetyConfig(wait_ns=ns_from_s(60)))
        mission.handle(Start(0, goal_id=42))
        mission.handle(Localized(ns_from_s(1.0), keyframe_id=7, matches=120))
        mission.handle(Obstacle(ns_from_s(2.0), "obstacle 0.45 m ahead"))
        assert mission.handle(Tick(ns_from_s(61.9))) is None
        held = mission.handle(Tick(ns_from_s(62.0)))
        assert (held.target, held.reason, held.detail) == (
            MissionState.ABORTED, "blocked", "blocked for 60.0 s: holding")

    def test_the_bumper_while_waiting_aborts(self) -> None:
        mission = following()
        mission.handle(Obstacle(ns_from_s(3.0), "obstacle 0.45 m ahead"))
        assert mission.handle(Bumper(ns_from_s(4.0))).reason == "bumper"

    def test_an_obstacle_while_localizing_changes_nothing(self) -> None:
        mission = lost()
        assert mission.handle(Obstacle(ns_from_s(3.0), "obstacle 0.2 m ahead")) is None


class TestTrueCauses:
    def test_localized_at_the_goal_is_arrived(self) -> None:
        for make in (lambda: Mission(CONFIG), lost):
            mission = make()
            if mission.state is MissionState.IDLE:
                mission.handle(Start(0, goal_id=42))
            arrived = mission.handle(Arrived(ns_from_s(3), 42))
            assert (arrived.target, arrived.reason) == (MissionState.ARRIVED, "arrived")
            assert Command.STOP in arrived.commands

    def test_no_route_fails_the_mission(self) -> None:
        mission = Mission(CONFIG)
        mission.handle(Start(0, goal_id=42))
        failed = mission.handle(NoRoute(1, "no route from key image 157 to goal key image 109"))
        assert (failed.target, failed.reason) == (MissionState.FAILED, "no_route")

    def test_lost_again_and_again_without_progress_fails(self) -> None:
        config = MissionConfig(lost_limit=3)
        mission = Mission(config)
        mission.handle(Start(0, goal_id=42))
        t = 1
        for episode in range(1, 4):
            mission.handle(Localized(t, keyframe_id=7, matches=120))
            outcome = mission.handle(Lost(t + 1, "no usable vision estimate"))
            t += 2
            if episode < 3:
                assert outcome.target is MissionState.LOST
        assert (outcome.target, outcome.reason) == (MissionState.FAILED, "lost_repeatedly")
        assert outcome.detail.startswith("lost 3 times without reaching a key image")

    def test_progress_restarts_the_count(self) -> None:
        mission = Mission(MissionConfig(lost_limit=2))
        mission.handle(Start(0, goal_id=42))
        for t in (1, 10, 20):
            mission.handle(Localized(t, keyframe_id=7, matches=120))
            mission.handle(KeyImageReached(t + 1, 8))
            assert mission.handle(Lost(t + 2, "no estimate")).target is MissionState.LOST

    def test_an_unknown_abort_cause_is_refused(self) -> None:
        with pytest.raises(ValueError, match="cause must be one of"):
            Abort(0, "because")


class TestTransitionTable:
    def test_every_state_has_a_row_and_every_edge_is_well_formed(self) -> None:
        assert set(m._TRANSITIONS) == set(MissionState)
        for row in m._TRANSITIONS.values():
            for edge in row.values():
                if edge is not None:
                    assert edge.reason in REASONS or edge.reason is m._CAUSE
                    assert edge.target in m._ENTRY_COMMANDS

    def test_final_states_are_absorbing(self) -> None:
        for state in FINAL_STATES:
            assert all(edge is None for edge in m._TRANSITIONS[state].values())

    def test_every_reason_is_reachable(self) -> None:
        used = {edge.reason for row in m._TRANSITIONS.values() for edge in row.values() if edge}
        # an Abort's reason is its cause; the lost limit redirects "lost"
        assert used - {m._CAUSE} | {*m.ABORT_CAUSES, "lost_repeatedly"} == set(REASONS)


inputs = st.one_of(
    st.builds(Start, st.just(0), st.integers(0, 9)),
    st.builds(Localized, st.just(0), st.integers(0, 9), st.integers(0, 300)),
    st.builds(LocalizationFailed, st.just(0), st.just("few matches")),
    st.builds(Lost, st.just(0), st.just("no estimate")),
    st.builds(Arrived, st.just(0), st.integers(0, 9)),
    st.builds(Bumper, st.just(0)), st.builds(Stall, st.just(0)),
    st.builds(Abort, st.just(0)), st.builds(Tick, st.just(0)),
)


@given(steps=st.lists(st.tuples(inputs, st.integers(0, ns_from_s(4))), max_size=40))
def test_random_inputs_never_reach_an_undefined_state(
    steps: list[tuple[m.MissionInput, int]],
) -> None:
    mission = Mission(CONFIG)
    t_ns = 0
    for template, dt_ns in steps:
        t_ns += dt_ns
        event = type(template)(t_ns, *[getattr(template, f) for f in template.__slots__[1:]])
        before = mission.state
        try:
            transition = mission.handle(event)
        except IllegalEventError as e:
            assert isinstance(e, VmnavError) and mission.state is before
            continue
        assert mission.state in MissionState
        if transition is None:
            assert mission.state is before
            continue
        assert before not in FINAL_STATES
        assert (transition.source, transition.target) == (before, mission.state)
        assert transition.reason in REASONS and transition.detail and transition.cause is event
        assert transition.t_ns == t_ns
        if transition.target is not MissionState.FOLLOWING:
            assert Command.STOP in transition.commands
