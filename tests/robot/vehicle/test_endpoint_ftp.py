"""MAVLink FTP of the memory and goal photos over real UDP, and the robot's user commands."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robot.vehicle.app_port import JobOutcome
from shared.mavlink.commands.user import GOTO_PHOTO, TEACH_START, TEACH_STOP, params_from_name
from shared.mavlink.dialect import mavlink
from shared.mavlink.ftp.gcs import Downloaded, FtpFailed, Listed, Uploaded
from shared.mavlink.ftp.payload import NakCode
from shared.memory.store import read_memory, thumbnail_path, write_memory
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Net
from tests.shared.memory.builders import loop_memory

ACCEPTED, DENIED = mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_DENIED
IN_PROGRESS, FAILED = mavlink.MAV_RESULT_IN_PROGRESS, mavlink.MAV_RESULT_FAILED


class TestMemory:
    def test_list_and_get_a_thumbnail(self, net: Net, tmp_path: Path,
                                      rng: np.random.Generator) -> None:
        write_memory(tmp_path / "memory", loop_memory(rng))
        net.ground.ftp.list_directory("/memory/thumbnails", net.now_ns)
        listed = net.until_event(net.ground.ftp)
        assert isinstance(listed, Listed)
        ids = sorted(read_memory(tmp_path / "memory").keyframes)
        assert sorted(e.name for e in listed.entries) == sorted(f"{i}.png" for i in ids)
        net.ground.ftp.get("/memory/thumbnails/5.png", net.now_ns)
        expected = thumbnail_path(tmp_path / "memory", 5).read_bytes()
        assert net.until_event(net.ground.ftp) == Downloaded("/memory/thumbnails/5.png", expected)

    def test_ardupilot_param_file_is_refused_at_once(self, net: Net) -> None:
        net.ground.ftp.get("@PARAM/param.pck?withdefaults=1", net.now_ns)
        start = net.now_ns
        failed = net.until_event(net.ground.ftp)
        assert isinstance(failed, FtpFailed) and failed.nak is NakCode.FILE_NOT_FOUND
        assert net.now_ns == start  # no retry needed


def photo_acks(net: Net) -> list[tuple[int, int, int]]:
    """(result, progress, result_param2) of every GOTO_PHOTO ACK the ground received."""
    return [(m.result, m.progress, m.result_param2) for _, m in net.ground.received
            if m.get_type() == "COMMAND_ACK" and m.command == GOTO_PHOTO]


class TestGotoPhoto:
    def test_uploaded_photo_is_looked_up_then_the_goal(self, net: Net, app: FakeApp,
                                                      tmp_path: Path) -> None:
        photo = bytes(range(256)) * 20
        net.ground.ftp.put("/upload/7.jpg", photo, net.now_ns)
        assert net.until_event(net.ground.ftp) == Uploaded("/upload/7.jpg", len(photo))
        assert net.command(GOTO_PHOTO, 7, final=False).result == IN_PROGRESS
        assert app.called("goto_image") == [(tmp_path / "upload" / "7.jpg", photo)]
        net.advance(1.0)  # looked up for a second: IN_PROGRESS every 0.4 s
        assert photo_acks(net) == [(IN_PROGRESS, 255, 0)] * 3
        app.job_outcomes.append(JobOutcome("photo", 68, "photo 7.jpg: key image 68, going there"))
        net.run(lambda: len(photo_acks(net)) == 4)
        assert photo_acks(net)[-1] == (ACCEPTED, 100, 68)
        net.advance(1.0)
        assert len(photo_acks(net)) == 4  # done: no more answers

    def test_a_photo_not_found_fails_the_command(self, net: Net, app: FakeApp,
                                                 tmp_path: Path) -> None:
        (tmp_path / "upload" / "2.png").write_bytes(b"png")
        assert net.command(GOTO_PHOTO, 2, final=False).result == IN_PROGRESS
        assert net.command(GOTO_PHOTO, 2).result == DENIED  # one photo at a time
        app.job_outcomes.append(JobOutcome("photo", None, "photo 2.png: not in the memory"))
        net.run(lambda: photo_acks(net)[-1][0] == FAILED)
        assert photo_acks(net)[-1] == (FAILED, 0, -1)
        assert "go to photo: another photo is being looked up" in net.ground.notices()
        assert net.command(GOTO_PHOTO, 2, final=False).result == IN_PROGRESS  # free again

    def test_a_missing_or_malformed_photo_is_denied_with_a_reason(
            self, net: Net, app: FakeApp, tmp_path: Path) -> None:
        (tmp_path / "upload" / "3.jpg").write_bytes(b"a")
        (tmp_path / "upload" / "3.png").write_bytes(b"b")
        for photo_id in (8, 1.5, 3):
            assert net.command(GOTO_PHOTO, photo_id).result == DENIED
        net.advance(0.1)
        assert net.ground.notices() == [
            "go to photo: want one uploaded /upload/8.<ext>, found none",
            "go to photo: photo id 1.5 is not an integer in 1..16777216",
            "go to photo: want one uploaded /upload/3.<ext>, found 3.jpg, 3.png"]
        assert app.called("goto_image") == []

    def test_a_photo_the_app_refuses_is_denied(self, net: Net, app: FakeApp,
                                               tmp_path: Path) -> None:
        (tmp_path / "upload" / "4.png").write_bytes(b"png")
        app.accept = False
        assert net.command(GOTO_PHOTO, 4).result == DENIED
        assert app.called("goto_image") == [(tmp_path / "upload" / "4.png", b"png")]


class TestTeach:
    def test_stop_answers_with_the_path_stored_or_fails(self, net: Net, app: FakeApp) -> None:
        ack = net.command(TEACH_STOP)
        assert (ack.result, ack.result_param2) == (ACCEPTED, 1)
        app.stored_path = None
        ack = net.command(TEACH_STOP)
        assert (ack.result, ack.result_param2) == (FAILED, -1)
        net.advance(0.1)
        assert net.ground.notices()[-1] == (
            "teach 'corridor': 0.12 m driven, a path needs 1.00 m: nothing stored")

    def test_start_with_a_name_then_stop(self, net: Net, app: FakeApp) -> None:
        assert net.command(TEACH_START, *params_from_name("corridor west 2")).result == ACCEPTED
        assert net.command(TEACH_STOP).result == ACCEPTED
        assert net.command(TEACH_START).result == ACCEPTED  # NaN params: the robot names it
        assert app.called("teach_start") == [("corridor west 2",), ("",)]
        assert app.called("teach_stop") == [()]

    def test_malformed_name_or_refusal_is_denied(self, net: Net, app: FakeApp) -> None:
        assert net.command(TEACH_START, 1.5).result == DENIED
        app.accept = False
        assert net.command(TEACH_STOP).result == DENIED
        net.advance(0.1)
        assert net.ground.notices() == [
            "teach start: parameters carry no valid path name", "teach stop: not teaching"]
        assert app.called("teach_start") == []
