"""``vmnav ground`` against a real vehicle endpoint over loopback UDP."""

from __future__ import annotations

import io
import logging
import re
import stat
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.mission import MissionState
from robot.vehicle.app_port import JobOutcome
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import WallClock
from shared.key_file import read_key_file
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.mavlink.signing import key_from_passphrase
from shared.memory.store import read_memory, thumbnail_path, write_memory
from shared.udp_link import UdpLink
from tests.ground.conftest import run_ground
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle
from tests.shared.memory.builders import loop_memory
from tools.bench.hostile_images import bogus_chunk_png
from tools.cli import main
from tools.ground_memory_cmd import id_ranges

Capsys = pytest.CaptureFixture[str]


def one_line_error(capsys: Capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("vmnav ground: "), err
    return err


def test_status_shows_the_vehicle_and_its_mode(vehicle: UdpVehicle, app: FakeApp,
                                               capsys: Capsys) -> None:
    app.update(mode=Mode.HOLD)
    assert run_ground(vehicle, "status") == 0
    shown = re.fullmatch(
        r"vehicle 1: mode HOLD, standby, battery 12\.6 V, mission item 0/0, no mission, "
        r"heartbeat (\d+\.\d) s ago\n", capsys.readouterr().out)
    # The age is on the wall clock: 0.0 s on an idle machine, more when the command waits
    # for a core between the HEARTBEAT and the print; never older than its --timeout.
    assert shown is not None and float(shown.group(1)) <= 3.0


def test_no_vehicle_is_one_line_within_the_timeout(capsys: Capsys) -> None:
    with UdpLink.open("udpin:127.0.0.1:0") as silent:
        start = time.monotonic()
        code = main(["ground", "--connect", f"udpout:127.0.0.1:{silent.local_port}",
                     "--timeout", "0.3", "params", "list"])
        elapsed_s = time.monotonic() - start
    assert code == 1 and elapsed_s < 1.0
    assert "no HEARTBEAT from a vehicle within 0.3 s" in one_line_error(capsys)


def test_params_list_get_set(vehicle: UdpVehicle, app: FakeApp, capsys: Capsys) -> None:
    assert run_ground(vehicle, "params", "list") == 0
    listed = capsys.readouterr().out.splitlines()
    assert "CTL_SPEED = 0.2" in listed and len(listed) >= 10
    assert run_ground(vehicle, "params", "set", "CTL_SPEED", "0.35") == 0
    assert capsys.readouterr().out == "CTL_SPEED = 0.35\n"
    assert app.configs[-1].control.speed_m_s == pytest.approx(0.35)
    assert run_ground(vehicle, "params", "get", "CTL_SPEED") == 0
    assert capsys.readouterr().out == "CTL_SPEED = 0.35\n"
    assert run_ground(vehicle, "params", "set", "CTL_SPEED", "5") == 1
    assert "kept CTL_SPEED = 0.35, not 5" in one_line_error(capsys)
    assert run_ground(vehicle, "params", "get", "NO_SUCH") == 1
    assert "parameter get NO_SUCH: no such parameter" in one_line_error(capsys)


def test_memory_list_and_get(vehicle: UdpVehicle, tmp_path: Path, rng: np.random.Generator,
                             capsys: Capsys) -> None:
    write_memory(tmp_path / "memory", loop_memory(rng))
    memory = read_memory(tmp_path / "memory")
    assert run_ground(vehicle, "memory", "list") == 0
    listed = capsys.readouterr()
    assert listed.out.splitlines() == [
        f"path {path.id} {path.name!r}: key images {id_ranges(list(path.keyframe_ids))} "
        f"({len(path.keyframe_ids)}, "
        f"{memory.keyframes[path.keyframe_ids[-1]].distance_m:.2f} m)"
        for path in memory.paths.values()]
    assert f"paths: {len(memory.paths)}, key images: {len(memory.keyframes)}" in listed.err
    out = tmp_path / "thumbs"
    assert run_ground(vehicle, "memory", "get", "5", "2", "--out", str(out)) == 0
    for key in (5, 2):
        assert (out / f"{key}.png").read_bytes() == \
            thumbnail_path(tmp_path / "memory", key).read_bytes()
    assert run_ground(vehicle, "memory", "get", "99", "--out", str(out)) == 1
    assert "FTP OPEN_FILE_RO /memory/thumbnails/99.png" in one_line_error(capsys)


def test_key_image_ids_are_listed_in_runs() -> None:
    assert id_ranges([0, 1, 2, 5, 7, 8]) == "0-2, 5, 7-8"
    assert id_ranges([3]) == "3" and id_ranges([]) == ""


def test_goto_key_uploads_and_starts_a_one_goal_mission(vehicle: UdpVehicle, app: FakeApp,
                                                        capsys: Capsys) -> None:
    assert run_ground(vehicle, "goto", "3") == 0
    assert app.called("start_mission") == [((Goal(3),), 0)]
    assert capsys.readouterr().out == "vehicle 1: going to key image 3\n"


def test_goto_an_unknown_key_is_refused(vehicle: UdpVehicle, app: FakeApp,
                                        capsys: Capsys) -> None:
    assert run_ground(vehicle, "goto", "99") == 1
    assert one_line_error(capsys) == (
        "vmnav ground: error: vehicle 1 refused the mission: MAV_MISSION_INVALID_PARAM1 "
        "(mission refused: item 0: no key image 99)\n")
    assert app.called("start_mission") == []


class ArrivingApp(FakeApp):
    """Arrives at the last goal as soon as the mission starts."""

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        super().start_mission(goals, first_seq)
        self.update(mission_state=MissionState.ARRIVED, mission_detail="at the goal",
                    reached_seqs=tuple(range(first_seq, first_seq + len(goals))))
        return True


@pytest.mark.parametrize("app", [ArrivingApp()], ids=["arriving"])
def test_goto_wait_reached(vehicle: UdpVehicle, app: FakeApp, capsys: Capsys) -> None:
    assert run_ground(vehicle, "goto", "4", "--wait", "--wait-timeout", "3") == 0
    assert capsys.readouterr().out.splitlines()[-1] == "vehicle 1: goal reached"


def test_goto_wait_not_reached(vehicle: UdpVehicle, app: FakeApp, capsys: Capsys) -> None:
    assert run_ground(vehicle, "goto", "4", "--wait", "--wait-timeout", "0.3") == 1
    assert one_line_error(capsys) == (
        "vmnav ground: goal not reached: still on the way after 0.3 s "
        "(last notice: mission localizing: localizing the start)\n")


class PhotoApp(FakeApp):
    """Looks a photo up as the robot does: a notice, then the outcome (key image 12, or
    not found when ``found`` is False)."""

    found = True

    def goto_image(self, path: Path) -> bool:
        super().goto_image(path)
        if self.found:
            text = (f"photo {path.name}: key image 12: 40 matches, 31 verified inliers "
                    "(accepted), going there")
        else:
            text = (f"photo {path.name}: not in the memory (best key image 3: 12 matches, "
                    "4 verified inliers (rejected))")
        self.notices.append((logging.INFO, text))
        self.job_outcomes.append(JobOutcome("photo", 12 if self.found else None, text))
        return True


def goal_photo(tmp_path: Path) -> Path:
    photo = tmp_path / "goal.jpg"
    photo.write_bytes(cv2.imencode(".jpg", np.full((60, 80), 128, np.uint8))[1].tobytes())
    return photo


@pytest.mark.parametrize("app", [PhotoApp()], ids=["photo"])
def test_goto_image_uploads_the_photo_and_says_where_it_was_found(
        vehicle: UdpVehicle, app: FakeApp, tmp_path: Path, capsys: Capsys) -> None:
    photo = goal_photo(tmp_path)
    assert run_ground(vehicle, "goto", "--image", str(photo)) == 0
    assert run_ground(vehicle, "goto", "--image", str(photo)) == 0  # a second one, new id
    assert [(path.name, data) for path, data in app.called("goto_image")] == [
        ("1.jpg", photo.read_bytes()), ("2.jpg", photo.read_bytes())]
    assert capsys.readouterr().out.splitlines()[-2:] == [
        "vehicle 1: photo goal.jpg (uploaded as photo 2) found at key image 12; going there",
        "  the robot: photo 2.jpg: key image 12: 40 matches, 31 verified inliers (accepted), "
        "going there"]


class LostPhotoApp(PhotoApp):
    found = False


@pytest.mark.parametrize("app", [LostPhotoApp()], ids=["lost-photo"])
def test_goto_image_not_in_the_memory_fails_at_once(
        vehicle: UdpVehicle, app: FakeApp, tmp_path: Path, capsys: Capsys) -> None:
    started = time.monotonic()
    assert run_ground(vehicle, "goto", "--image", str(goal_photo(tmp_path)), "--wait") == 1
    assert time.monotonic() - started < 60  # not --wait-timeout's 600 s
    assert one_line_error(capsys) == (
        "vmnav ground: error: vehicle 1 answered GOTO_PHOTO with MAV_RESULT_FAILED "
        "(photo 1.jpg: not in the memory (best key image 3: 12 matches, 4 verified inliers "
        "(rejected)))\n")


def test_goto_image_refuses_a_bomb_before_uploading_it(
        vehicle: UdpVehicle, app: FakeApp, tmp_path: Path, capsys: Capsys) -> None:
    photo = tmp_path / "goal.png"
    photo.write_bytes(bogus_chunk_png(np.random.default_rng(0)))
    assert run_ground(vehicle, "goto", "--image", str(photo)) == 1
    assert one_line_error(capsys) == (
        f"vmnav ground: error: {photo}: corrupt PNG: chunk tEXt at byte 33 declares "
        "2147483647 bytes, the file has 3163 after its header\n")
    assert app.called("goto_image") == []


def test_goto_needs_exactly_one_goal(vehicle: UdpVehicle, capsys: Capsys) -> None:
    assert run_ground(vehicle, "goto") == 1
    assert "give either a key image id KEY or --image PHOTO" in one_line_error(capsys)


def test_teach_start_and_stop_reach_the_app(vehicle: UdpVehicle, app: FakeApp,
                                            capsys: Capsys) -> None:
    assert run_ground(vehicle, "teach", "start", "corridor 2") == 0
    capsys.readouterr()
    assert run_ground(vehicle, "teach", "stop") == 0
    assert capsys.readouterr().out.splitlines() == [
        "vehicle 1: teaching stopped, path 1 stored",
        "  the robot: path 1 'corridor': 12 key images, 0 junction(s)"]
    assert app.called("teach_start") == [("corridor 2",)] and app.called("teach_stop") == [()]
    app.stored_path = None
    assert run_ground(vehicle, "teach", "stop") == 1
    assert one_line_error(capsys) == (
        "vmnav ground: error: vehicle 1 answered TEACH_STOP with MAV_RESULT_FAILED (teach "
        "'corridor': 0.12 m driven, a path needs 1.00 m: nothing stored)\n")
    app.accept = False
    capsys.readouterr()
    assert run_ground(vehicle, "teach", "stop") == 1
    assert one_line_error(capsys) == ("vmnav ground: error: vehicle 1 answered TEACH_STOP "
                                      "with MAV_RESULT_DENIED (teach stop: not teaching)\n")


def test_stop_force_disarms_and_arm_arms(vehicle: UdpVehicle, app: FakeApp,
                                          capsys: Capsys) -> None:
    assert run_ground(vehicle, "stop") == 0
    assert "vehicle 1: emergency stop accepted in " in capsys.readouterr().out
    assert run_ground(vehicle, "arm") == 0
    assert app.called("arm") == [(False, True), (True, False)]


def test_drive_needs_a_terminal(vehicle: UdpVehicle, monkeypatch: pytest.MonkeyPatch,
                                capsys: Capsys) -> None:
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert run_ground(vehicle, "drive") == 1
    assert one_line_error(capsys) == (
        "vmnav ground: error: stdin: not a terminal: drive reads keys, run it from one\n")


def test_watch_prints_telemetry_lines(vehicle: UdpVehicle, app: FakeApp, capsys: Capsys) -> None:
    app.update(odom_pose=(1.5, -0.25, 0.5))
    assert run_ground(vehicle, "watch", "--duration", "1.1") == 0
    lines = capsys.readouterr().out.splitlines()
    kinds = {line.split()[4] for line in lines}
    assert {"HEARTBEAT:", "SYS_STATUS:", "ODOMETRY:", "MISSION_CURRENT:"} <= kinds
    assert any(line.endswith("vehicle 1  HEARTBEAT: mode MANUAL, standby") for line in lines)
    assert any("ODOMETRY: x +1.50 m, y -0.25 m, yaw +28.6 deg" in line for line in lines)


def test_keygen_writes_a_key_both_ends_and_mavproxy_can_use(tmp_path: Path,
                                                            capsys: Capsys) -> None:
    path = tmp_path / "vmnav.key"
    assert main(["ground", "keygen", str(path)]) == 0
    out = capsys.readouterr().out
    passphrase = path.read_text().strip()
    assert read_key_file(path) == key_from_passphrase(passphrase)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert passphrase not in out  # the secret is read from the file, never printed
    assert f"vmnav robot --key {path.name}" in out and f"vmnav ground --key {path}" in out
    assert f'echo "udpout:ROBOT:14550 $(cat {path})" >> ~/.mavproxy/signing.keys' in out
    assert main(["ground", "keygen", str(path)]) == 1
    assert "exists: a new key never replaces one" in one_line_error(capsys)
    assert path.read_text().strip() == passphrase


def test_an_unsigned_link_open_to_the_network_is_refused(capsys: Capsys) -> None:
    assert main(["ground", "--connect", "udpin:0.0.0.0:0", "status"]) == 1
    assert "--connect udpin:0.0.0.0:0: an unsigned link open to the network" in \
        one_line_error(capsys)


def test_a_signed_station_talks_to_a_signed_vehicle(tmp_path: Path, capsys: Capsys) -> None:
    key = tmp_path / "vmnav.key"
    assert main(["ground", "keygen", str(key)]) == 0
    app = FakeApp()
    app.update(mode=Mode.HOLD)
    vehicle = make_vehicle(tmp_path, app, WallClock(), key=read_key_file(key))
    vehicle.start_thread()
    try:
        assert main(["ground", "--key", str(key), "--connect",
                     f"udpout:127.0.0.1:{vehicle.link.local_port}", "status"]) == 0
        assert capsys.readouterr().out.splitlines()[-1].startswith("vehicle 1: mode HOLD")
        stats = vehicle.endpoint.stats()
        assert stats.signing is not None and stats.signing.good > 0 and stats.bad_packets == 0
    finally:
        vehicle.close()
