"""Goal missions over real UDP: upload, validation, start, progress reports."""

from __future__ import annotations

from robot.mission import MissionState
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.gcs import DownloadDone, Operation, OperationRefused, UploadDone
from shared.mavlink.mission.goal import Goal
from shared.mavlink.mission.items import MissionItem
from shared.mavlink.modes import Mode
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Net

GOALS = (Goal(2), Goal(5), Goal(6))
CUSTOM = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


def upload(net: Net, items: tuple[MissionItem, ...]) -> object:
    net.ground.send(*net.ground.mission.upload(items, net.now_ns))
    return net.until_event(net.ground.mission)


def download(net: Net) -> tuple[MissionItem, ...]:
    net.ground.send(*net.ground.mission.download(net.now_ns))
    event = net.until_event(net.ground.mission)
    assert isinstance(event, DownloadDone)
    return event.items


def items_of(goals: tuple[Goal, ...]) -> tuple[MissionItem, ...]:
    return tuple(goal.to_item() for goal in goals)


class TestUpload:
    def test_goals_are_validated_stored_and_not_started(self, net: Net, app: FakeApp) -> None:
        assert upload(net, items_of(GOALS)) == UploadDone(3)
        assert app.called("validate_goals") == [(GOALS,)]
        assert app.called("start_mission") == []
        assert download(net) == items_of(GOALS)

    def test_unknown_key_image_is_refused_and_the_old_mission_kept(
            self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        refused = upload(net, items_of((Goal(1), Goal(99))))
        assert refused == OperationRefused(Operation.UPLOAD, mavlink.MAV_MISSION_INVALID_PARAM1)
        assert net.ground.notices() == [
            "mission refused: item 1: no key image 99"]
        assert download(net) == items_of(GOALS)

    def test_unreachable_goal_and_foreign_items_are_refused(self, net: Net, app: FakeApp) -> None:
        app.unreachable = frozenset({4})
        assert upload(net, items_of((Goal(4),))).result == mavlink.MAV_MISSION_DENIED
        waypoint = MissionItem(command=mavlink.MAV_CMD_NAV_WAYPOINT)
        assert upload(net, (waypoint,)).result == mavlink.MAV_MISSION_UNSUPPORTED
        assert download(net) == ()

    def test_no_upload_or_clear_while_the_mission_runs(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)
        assert upload(net, items_of((Goal(1),))).result == mavlink.MAV_MISSION_DENIED
        net.ground.send(*net.ground.mission.clear(net.now_ns))
        assert net.until_event(net.ground.mission).result == mavlink.MAV_MISSION_DENIED
        app.update(mode=Mode.HOLD)
        assert upload(net, items_of((Goal(1),))) == UploadDone(1)


class TestStart:
    def test_mission_start_runs_the_chosen_items(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        ack = net.command(mavlink.MAV_CMD_MISSION_START, 1, 2)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert app.called("start_mission") == [(GOALS[1:], 1)]
        assert net.command(mavlink.MAV_CMD_MISSION_START, 2, 5).result == \
            mavlink.MAV_RESULT_DENIED

    def test_auto_starts_from_the_current_item(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        assert net.command(mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 1).result == \
            mavlink.MAV_RESULT_ACCEPTED
        assert net.ground.of_type("MISSION_CURRENT")[-1].seq == 1
        assert net.command(mavlink.MAV_CMD_DO_SET_MODE, CUSTOM, 10).result == \
            mavlink.MAV_RESULT_ACCEPTED
        assert app.called("start_mission") == [(GOALS[1:], 1)]
        assert app.called("set_mode") == []

    def test_px4_mission_mode_starts_too(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        assert net.command(mavlink.MAV_CMD_DO_SET_MODE, CUSTOM, 4, 4).result == \
            mavlink.MAV_RESULT_ACCEPTED
        assert app.called("start_mission") == [(GOALS, 0)]

    def test_a_start_the_app_refuses_is_denied(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        app.accept = False
        assert net.command(mavlink.MAV_CMD_MISSION_START, 0, 2).result == \
            mavlink.MAV_RESULT_DENIED


class TestProgress:
    def test_reached_items_current_item_and_state_changes(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)
        net.advance(0.1)
        app.update(mission_state=MissionState.FOLLOWING, mission_detail="localized at key 1")
        net.run(lambda: len(net.ground.of_type("STATUSTEXT")) == 2)
        assert net.ground.notices() == [
            "mission localizing: localizing the start", "mission following: localized at key 1"]
        assert net.ground.of_type("MISSION_CURRENT")[-1].mission_state == \
            mavlink.MISSION_STATE_ACTIVE

        app.update(reached_seqs=(0,), mission_seq=1)
        net.run(lambda: bool(net.ground.of_type("MISSION_ITEM_REACHED")))
        current = net.ground.of_type("MISSION_CURRENT")[-1]
        assert (current.seq, current.total, current.mission_state) == (
            1, 3, mavlink.MISSION_STATE_ACTIVE)

        app.update(reached_seqs=(0, 1, 2), mission_seq=2, mission_state=MissionState.ARRIVED,
                   mission_detail="key image 6 reached")
        net.run(lambda: len(net.ground.of_type("MISSION_ITEM_REACHED")) == 3)
        net.advance(1.0)
        assert [m.seq for m in net.ground.of_type("MISSION_ITEM_REACHED")] == [0, 1, 2]
        assert net.ground.of_type("STATUSTEXT")[-1].text == "mission arrived: key image 6 reached"
        current = net.ground.of_type("MISSION_CURRENT")[-1]
        assert (current.seq, current.mission_state) == (2, mavlink.MISSION_STATE_COMPLETE)

    def test_a_new_run_reports_its_items_again(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)
        app.update(reached_seqs=(0,), mission_seq=1)
        net.advance(0.5)
        net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)  # the app restarts with no items
        app.update(reached_seqs=(0,), mission_seq=1)
        net.advance(0.5)
        assert [m.seq for m in net.ground.of_type("MISSION_ITEM_REACHED")] == [0, 0]

    def test_aborted_mission_is_a_warning_and_paused(self, net: Net, app: FakeApp) -> None:
        upload(net, items_of(GOALS))
        net.command(mavlink.MAV_CMD_MISSION_START, 0, 2)
        net.advance(0.1)
        app.update(mission_state=MissionState.ABORTED, mission_detail="bumper")
        net.run(lambda: len(net.ground.of_type("STATUSTEXT")) == 2)
        notice = net.ground.of_type("STATUSTEXT")[-1]
        assert (notice.severity, notice.text) == (mavlink.MAV_SEVERITY_WARNING,
                                                  "mission aborted: bumper")
        assert net.ground.of_type("MISSION_CURRENT")[-1].mission_state == \
            mavlink.MISSION_STATE_PAUSED


class TestOutcome:
    def servo_states(self, net: Net) -> list[int]:
        return [m.state for m in net.ground.of_type("VISUAL_SERVO_STATUS")]

    def test_each_change_of_state_goes_out_at_once(self, net: Net, app: FakeApp) -> None:
        net.advance(0.1)
        seen = len(self.servo_states(net))
        app.update(mission_state=MissionState.LOCALIZING, run_count=1, goal_key=4)
        net.advance(0.05)  # well before the stream's next slot
        app.update(mission_state=MissionState.FAILED, mission_detail="no match")
        net.advance(0.05)
        assert self.servo_states(net)[seen:] == [mavlink.VTR_STATE_LOCALIZING,
                                                 mavlink.VTR_STATE_FAILED]

    def test_a_run_that_ended_between_two_polls_is_seen_starting(
            self, net: Net, app: FakeApp) -> None:
        app.update(mission_state=MissionState.ARRIVED, run_count=1, goal_key=4)
        net.advance(0.1)
        seen = len(self.servo_states(net))
        app.update(run_count=2)  # a second run to the same goal came and went
        net.advance(0.05)
        assert self.servo_states(net)[seen:] == [mavlink.VTR_STATE_LOCALIZING,
                                                 mavlink.VTR_STATE_ARRIVED]
        assert net.ground.notices()[-1] == "mission arrived"

    def test_the_outcome_stays_in_the_stream(self, net: Net, app: FakeApp) -> None:
        app.update(mission_state=MissionState.FOLLOWING, run_count=1)
        net.advance(0.1)
        app.update(mission_state=MissionState.ABORTED, mission_detail="bumper")
        net.advance(3.0)
        assert self.servo_states(net)[-4:] == [mavlink.VTR_STATE_ABORTED] * 4
