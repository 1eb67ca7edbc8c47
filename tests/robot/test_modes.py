"""The robot's top-level table (robot/modes.py): each rule, every refusal, every illegal pair."""

from __future__ import annotations

import itertools
import logging
from dataclasses import replace
from pathlib import Path

import pytest

from robot.mode_events import (
    Arm,
    BaseBack,
    BaseLost,
    GcsLost,
    GoalGone,
    GotoPhoto,
    PathNotStored,
    PhotoFound,
    PhotoNotFound,
    RunEnded,
    SetMode,
    StartGoals,
    TeachStart,
    TeachStop,
    TimeLimit,
)
from robot.modes import _TRANSITIONS, Action, Activity, Drive, TopState, decide, drive_of
from shared.errors import IllegalEventError
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode

IDLE = TopState()
RUNNING = TopState(mode=Mode.AUTO, activity=Activity.RUNNING)
TEACHING = TopState(mode=Mode.MANUAL, activity=Activity.TEACHING)
PHOTO = GotoPhoto(Path("1.png"))
FOUND = PhotoFound(7, "photo 1.png: key image 7 (40 matches), going there")

#: One event of each type (PathStored carries a memory: its edges are the same as
#: PathNotStored's but for ADOPT_MEMORY).
EVENTS = (SetMode(Mode.MANUAL), Arm(False), StartGoals((Goal(3),), 0), PHOTO, FOUND,
          PhotoNotFound(logging.WARNING, "photo 1.png: not in the memory"),
          TeachStart("east"), TeachStop(), PathNotStored("too short"), RunEnded(False),
          GoalGone("mission: no key image 3"), BaseLost(True), BaseBack(), GcsLost("hold"))


class TestRule1Modes:
    def test_the_robot_starts_in_hold_armed_and_idle(self) -> None:
        assert TopState(Mode.HOLD, True, Activity.IDLE, False, 0) == IDLE
        assert drive_of(IDLE) is Drive.STOP

    def test_a_mode_is_entered_with_its_notice_and_the_stick_dropped(self) -> None:
        d = decide(IDLE, SetMode(Mode.MANUAL))
        assert d.state.mode is Mode.MANUAL and d.actions == (Action.SAY_MODE, Action.DROP_STICK)
        assert drive_of(d.state) is Drive.STICK
        again = decide(d.state, SetMode(Mode.MANUAL))
        assert again.actions == (Action.DROP_STICK,)  # no notice: the mode did not change

    def test_guided_without_a_run_is_stopped(self) -> None:
        assert drive_of(decide(IDLE, SetMode(Mode.GUIDED)).state) is Drive.STOP

    def test_goals_run_in_auto_and_the_last_one_holds(self) -> None:
        d = decide(IDLE, StartGoals((Goal(3), Goal(5)), 0))
        assert (d.state.mode, d.state.activity) == (Mode.AUTO, Activity.RUNNING)
        assert d.actions == (Action.START_GOALS,) and drive_of(d.state) is Drive.RUN
        more = decide(d.state, RunEnded(next_goal=True))
        assert more.state == d.state and more.actions == (Action.NEXT_GOAL,)
        last = decide(d.state, RunEnded(next_goal=False))
        assert (last.state.mode, last.state.activity) == (Mode.HOLD, Activity.IDLE)
        assert last.actions == (Action.STOP,)


class TestRule2LeavingAMissionMode:
    @pytest.mark.parametrize("mode", [Mode.HOLD, Mode.MANUAL, Mode.GUIDED])
    def test_another_mode_aborts_the_run(self, mode: Mode) -> None:
        d = decide(RUNNING, SetMode(mode))
        assert (d.state.mode, d.state.activity) == (mode, Activity.IDLE)
        assert d.actions == (Action.END_RUN, Action.SAY_MODE, Action.DROP_STICK)
        assert d.why == f"mode {mode.name}"

    def test_the_same_mode_keeps_the_run(self) -> None:
        d = decide(RUNNING, SetMode(Mode.AUTO))
        assert d.state == RUNNING and d.actions == (Action.DROP_STICK,)

    def test_the_gcs_failsafe_hold_aborts_the_run(self) -> None:
        d = decide(RUNNING, GcsLost("hold"))
        assert (d.state.mode, d.state.activity) == (Mode.HOLD, Activity.IDLE)
        assert Action.END_RUN in d.actions
        assert (d.cause, d.why) == ("gcs_lost", "ground heartbeat lost: mode HOLD")

    def test_a_time_limit_ends_the_run_in_hold_with_its_cause(self) -> None:
        d = decide(RUNNING, TimeLimit("time limit 90 s reached"))
        assert (d.state.mode, d.state.activity) == (Mode.HOLD, Activity.IDLE)
        assert (d.cause, d.why) == ("time_limit", "time limit 90 s reached")
        assert decide(IDLE, TimeLimit("late")).actions == ()

    def test_a_forced_disarm_ends_the_run_as_the_emergency_stop(self) -> None:
        d = decide(RUNNING, Arm(False, emergency=True))
        assert (d.state.armed, d.cause, d.why) == (False, "e_stop", "emergency stop")
        assert decide(RUNNING, Arm(False)).cause == "disarmed"

    def test_auto_again_restarts(self) -> None:
        d = decide(RUNNING, StartGoals((Goal(3),), 1))
        assert d.state == RUNNING and d.actions == (Action.END_RUN, Action.START_GOALS)
        assert d.why == "a new mission started"


class TestRule3Disarmed:
    def test_disarming_ends_the_run_in_hold(self) -> None:
        d = decide(RUNNING, Arm(False))
        assert (d.state.mode, d.state.armed, d.state.activity) == (Mode.HOLD, False,
                                                                   Activity.IDLE)
        assert d.actions == (Action.END_RUN,) and d.why == "disarmed"

    @pytest.mark.parametrize("mode", list(Mode))
    def test_nothing_moves_disarmed(self, mode: Mode) -> None:
        for activity in Activity:
            assert drive_of(TopState(mode, False, activity)) is Drive.STOP

    @pytest.mark.parametrize("event, text", [
        (StartGoals((Goal(3),), 0), "mission refused: disarmed"),
        (PHOTO, "photo goal refused: disarmed")])
    def test_goals_and_photos_are_refused(self, event, text: str) -> None:
        disarmed = replace(IDLE, armed=False)
        d = decide(disarmed, event)
        assert d.refused and d.state == disarmed and d.say == text

    def test_a_photo_found_after_disarming_is_dropped(self) -> None:
        d = decide(TopState(armed=False, photos_pending=1), FOUND)
        assert d.refused and d.say == "photo goal dropped: disarmed"
        assert d.state.photos_pending == 0 and d.state.activity is Activity.IDLE


class TestRule4Teaching:
    def test_teaching_enters_manual(self) -> None:
        d = decide(IDLE, TeachStart("east"))
        assert (d.state.mode, d.state.activity) == (Mode.MANUAL, Activity.TEACHING)
        assert d.actions == (Action.SAY_MODE, Action.DROP_STICK, Action.START_TEACH)

    def test_stopping_hands_the_path_to_the_worker_in_any_mode(self) -> None:
        for mode in Mode:
            d = decide(replace(TEACHING, mode=mode), TeachStop())
            assert d.state.activity is Activity.IDLE and d.state.mode is mode
            assert d.actions == (Action.STOP, Action.SAVE_PATH)

    @pytest.mark.parametrize("state, event, text", [
        (RUNNING, TeachStart("x"), "teach start refused: a mission is running"),
        (TEACHING, TeachStart("x"), "teach start refused: already teaching"),
        (IDLE, TeachStop(), "teach stop refused: not teaching"),
        (RUNNING, TeachStop(), "teach stop refused: not teaching"),
        (TEACHING, StartGoals((Goal(3),), 0), "mission refused: teaching"),
        (TEACHING, PHOTO, "photo goal refused: teaching"),
        (replace(TEACHING, photos_pending=1), FOUND, "photo goal dropped: teaching")])
    def test_refusals(self, state: TopState, event, text: str) -> None:
        d = decide(state, event)
        assert d.refused and d.say == text and d.actions == (Action.SAY,)
        assert replace(d.state, photos_pending=state.photos_pending) == state

    def test_a_path_not_stored_is_told_whatever_the_robot_does(self) -> None:
        for state in (IDLE, RUNNING, TEACHING):
            d = decide(state, PathNotStored("too short"))
            assert d.state == state and d.actions == (Action.SAY_EVENT,)


class TestRule5Photos:
    def test_a_photo_goes_to_the_worker_and_its_result_comes_back(self) -> None:
        d = decide(IDLE, PHOTO)
        assert d.actions == (Action.FIND_PHOTO,) and d.state.photos_pending == 1
        found = decide(d.state, FOUND)
        assert (found.state.mode, found.state.activity) == (Mode.GUIDED, Activity.RUNNING)
        assert found.actions == (Action.SAY_EVENT, Action.START_PHOTO_GOAL)
        assert found.state.photos_pending == 0
        missed = decide(d.state, PhotoNotFound(logging.WARNING, "not in the memory"))
        assert missed.state == IDLE and missed.actions == (Action.SAY_EVENT,)

    def test_a_photo_found_during_a_run_replaces_it(self) -> None:
        d = decide(replace(RUNNING, photos_pending=1), FOUND)
        assert d.state.mode is Mode.GUIDED and d.state.activity is Activity.RUNNING
        assert d.actions == (Action.SAY_EVENT, Action.END_RUN, Action.START_PHOTO_GOAL)
        assert d.why == "a new goal"


class TestRule6RunsEnd:
    def test_a_goal_gone_from_the_memory_holds(self) -> None:
        d = decide(RUNNING, GoalGone("mission: no key image 3"))
        assert (d.state.mode, d.state.activity) == (Mode.HOLD, Activity.IDLE)
        assert d.actions == (Action.SAY_EVENT,)


class TestRule7BaseLost:
    def test_hold_ends_the_run(self) -> None:
        d = decide(RUNNING, BaseLost(hold=True))
        assert d.state == TopState(Mode.HOLD, True, Activity.IDLE, base_lost=True)
        assert d.actions == (Action.SAY, Action.END_RUN)
        assert d.say == "base not reporting: stopped, mission held"
        assert d.why == "the base stopped reporting"

    def test_continue_pauses_the_run_until_the_base_is_back(self) -> None:
        d = decide(RUNNING, BaseLost(hold=False))
        assert d.state == replace(RUNNING, base_lost=True)
        assert d.say == "base not reporting: stopped, mission paused"
        assert drive_of(d.state) is Drive.STOP
        back = decide(d.state, BaseBack())
        assert back.state == RUNNING and back.actions == (Action.SAY_BASE_BACK,)
        assert drive_of(back.state) is Drive.RUN

    def test_without_a_run_the_robot_stops(self) -> None:
        for state in (replace(IDLE, mode=Mode.MANUAL), TEACHING):
            d = decide(state, BaseLost(hold=True))
            assert d.say == "base not reporting: stopped" and drive_of(d.state) is Drive.STOP
            assert d.state.activity is state.activity


class TestRule8GcsFailsafe:
    @pytest.mark.parametrize("state", [IDLE, RUNNING, TEACHING])
    def test_stop_drops_the_stick_and_continue_changes_nothing(self, state: TopState) -> None:
        assert decide(state, GcsLost("stop")).actions == (Action.DROP_STICK,)
        kept = decide(state, GcsLost("continue"))
        assert kept.state == state and kept.actions == ()

    def test_hold_without_a_run_enters_hold(self) -> None:
        d = decide(replace(IDLE, mode=Mode.MANUAL), GcsLost("hold"))
        assert d.state.mode is Mode.HOLD and Action.END_RUN not in d.actions


class TestRule9IllegalPairs:
    def test_every_pair_missing_from_the_table_raises(self) -> None:
        states = {Activity.IDLE: replace(IDLE, photos_pending=1),
                  Activity.RUNNING: replace(RUNNING, photos_pending=1),
                  Activity.TEACHING: replace(TEACHING, photos_pending=1)}
        illegal = [(activity, type(event)) for activity, event
                   in itertools.product(Activity, EVENTS)
                   if type(event) not in _TRANSITIONS[activity]]
        assert sorted((a.name, e.__name__) for a, e in illegal) == [
            ("IDLE", "GoalGone"), ("IDLE", "RunEnded"),
            ("TEACHING", "GoalGone"), ("TEACHING", "RunEnded")]
        for activity, event in itertools.product(Activity, EVENTS):
            if type(event) in _TRANSITIONS[activity]:
                decide(states[activity], event)
                continue
            with pytest.raises(IllegalEventError, match=type(event).__name__):
                decide(states[activity], event)

    @pytest.mark.parametrize("event", [FOUND, PhotoNotFound(logging.ERROR, "unreadable")])
    def test_a_photo_result_with_none_pending_raises(self, event) -> None:
        with pytest.raises(IllegalEventError, match="not allowed in state IDLE"):
            decide(IDLE, event)
