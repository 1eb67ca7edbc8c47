"""``vmnav demo`` end to end (lock-step: teach a short route, repeat it from an offset), its
bad input, and the error measure against the taught path."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from pymavlink import mavutil

from robot.mission import MissionState
from robot.mission_run import CycleRecord
from shared.calibration import write_camera
from shared.camera_model import CameraModel
from shared.interfaces import BaseState
from shared.logs.reader import log_info
from shared.memory import read_memory
from tests.shared.memory.builders import folder_bytes, memory_without_manifest
from tools.cli import main
from tools.figures.demo_plots import VIDEO_EVERY
from tools.figures.demo_report import following_errors, plan_references, track_errors
from tools.harness.demo import CycleSample

REPORT_KEYS = ("reached_goal", "final_position_error_m", "lateral_rms_m", "lateral_max_m",
               "heading_rms_deg", "key_images_route", "key_images_reached", "distance_m",
               "sim_time_s", "wall_time_s", "mean_matches", "loop_ms_p50", "loop_ms_p95",
               "lost_events", "events")


@pytest.mark.slow
def test_the_robot_arrives_close_to_the_taught_path(short_demo) -> None:
    code, out, cpu_s = short_demo
    report = json.loads((out / "report.json").read_text())
    assert code == 0
    assert all(key in report for key in REPORT_KEYS)
    assert report["reached_goal"] and report["state"] == "arrived"
    assert report["key_images_reached"] == report["key_images_route"] >= 5
    assert report["final_position_error_m"] < 0.15
    assert report["lateral_rms_m"] < 0.05 and report["lateral_max_m"] < 0.10
    assert report["lost_events"] == 0
    # Faster than real time, given a core: the whole demo costs less CPU time than the
    # time it simulates (the teach of each path at least from its first key image to its
    # last). On the wall clock (the report's wall_time_s) that holds only while no other
    # process loads the machine.
    memory = read_memory(out / "memory")
    taught_s = sum(
        (memory.keyframes[path.keyframe_ids[-1]].t_ns - memory.keyframes[path.keyframe_ids[0]].t_ns)
        / 1e9 for path in memory.paths.values())
    assert cpu_s < taught_s + report["sim_time_s"]
    assert [e["reason"] for e in report["events"] if e["kind"] == "transition"] == [
        "start", "localized", "arrived"]


@pytest.mark.slow
def test_the_goal_went_through_the_ground_station_over_udp(short_demo) -> None:
    _, out, _ = short_demo
    dispatch = json.loads((out / "report.json").read_text())["dispatch"]
    assert dispatch["transport"] == "MAVLink over loopback UDP"
    assert dispatch["ground_saw_reached"] is True
    assert 0 < dispatch["mission_upload_ms"] < 1000
    (tlog,) = (out / "logs").glob("ground-*.tlog")
    types = []
    reader = mavutil.mavlink_connection(str(tlog))
    while (msg := reader.recv_match()) is not None:
        types.append(msg.get_type())
    for expected in ("MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ACK", "COMMAND_LONG",
                     "MISSION_ITEM_REACHED"):
        assert expected in types
    info = log_info(out / "logs" / "ground-0001.mcap")
    assert info.complete and info.message_count >= len(types)
    assert "/mavlink/in/VISUAL_SERVO_STATUS" in {t.topic for t in info.topics}


@pytest.mark.slow
def test_log_dump_decodes_the_vmnav_messages_of_the_ground_tlog(short_demo) -> None:
    """The ground station's tlog of the demo, written by the real station from the real
    robot's traffic: `vmnav log dump` (pymavlink's mavlogdump, our dialect) names every
    message; its VISUAL_SERVO_STATUS reached the goal."""
    _, out, _ = short_demo
    (tlog,) = (out / "logs").glob("ground-*.tlog")
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(root), *filter(None, [os.environ.get("PYTHONPATH")])])}
    done = subprocess.run([sys.executable, "-m", "tools.cli", "log", "dump", str(tlog),
                           "--format", "json"], capture_output=True, text=True, env=env,
                          cwd=root, timeout=300)
    assert (done.returncode, done.stderr) == (0, "")
    types = [json.loads(line)["meta"]["type"] for line in done.stdout.splitlines()]
    assert "VISUAL_SERVO_STATUS" in types
    assert not [t for t in types if t.startswith("UNKNOWN")]
    goal = json.loads((out / "report.json").read_text())["goal_key_image"]
    last = [json.loads(line)["data"] for line in done.stdout.splitlines()
            if '"VISUAL_SERVO_STATUS"' in line][-1]
    assert last["goal_key"] == goal


@pytest.mark.slow
def test_it_writes_the_plots(short_demo) -> None:
    _, out, _ = short_demo
    for name in ("topdown.png", "errors_vs_distance.png", "image_errors.png", "matches.png"):
        assert (out / name).stat().st_size > 10_000
    assert not (out / "demo.mp4").exists()


@pytest.mark.slow
def test_a_goal_not_in_memory_is_one_line_and_reuses_the_memory(short_demo, capsys) -> None:
    _, out, _ = short_demo
    before = folder_bytes(out)
    started = time.perf_counter()
    code = main(["demo", "--world", str(out.parent / "lab_short.toml"), "--routes",
                 "east_a,east_b", "--goal", "999", "--out", str(out), "--no-video"])
    err = capsys.readouterr().err
    assert code == 1 and time.perf_counter() - started < 5.0
    assert err.count("\n") == 1 and "key image 999 is not in the memory" in err
    assert folder_bytes(out) == before  # refused before a log or a video was opened


@pytest.mark.slow
def test_a_memory_taught_otherwise_is_refused_before_teaching(short_demo, capsys) -> None:
    _, out, _ = short_demo
    code = main(["demo", "--routes", "corridor", "--seed", "7", "--out", str(out), "--no-video"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "taught with another world, seed" in err


def test_a_memory_of_another_camera_is_refused_and_kept(short_demo, tmp_path, capsys) -> None:
    _, out, _ = short_demo
    camera = tmp_path / "camera.json"
    write_camera(camera, dataclasses.replace(CameraModel.default(), fov_deg=180.0))
    before = folder_bytes(out)
    code = main(["demo", "--routes", "corridor", "--calibration", str(camera), "--out", str(out),
                 "--no-video"])
    err = capsys.readouterr().err
    assert code == 1 and err == (f"vmnav demo: error: {out / 'memory'}: holds a memory taught "
                                 "with another world, seed, routes or camera (or without "
                                 "teach.json): remove it or choose another --out\n")
    assert folder_bytes(out) == before


def test_files_without_a_manifest_are_not_taught_over(tmp_path, capsys, rng) -> None:
    memory = tmp_path / "out" / "memory"
    before = memory_without_manifest(memory, rng)
    code = main(["demo", "--routes", "corridor", "--out", str(tmp_path / "out"), "--no-video"])
    err = capsys.readouterr().err
    assert code == 1 and err == (f"vmnav demo: error: memory {memory}: manifest.json missing but "
                                 "the folder holds 21 files; restore it or point --memory to an "
                                 "empty folder\n")
    assert folder_bytes(memory) == before
    assert [p.name for p in memory.parent.iterdir()] == ["memory"]  # no teach.json either


@pytest.mark.parametrize(("args", "message"), [
    (["--world", "atlantis"], "atlantis"),
    (["--routes", "nowhere"], "unknown route 'nowhere'"),
    (["--moved", "2"], "--moved"),
])
def test_bad_input_is_one_line(tmp_path, capsys, args, message) -> None:
    code = main(["demo", "--out", str(tmp_path / "out"), "--no-video", *args])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and message in err


class TestTrackErrors:
    def test_left_is_positive_and_heading_is_relative(self) -> None:
        reference = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
        poses = np.array([[0.5, 0.1, 0.2], [1.5, -0.05, -0.1]])
        errors = track_errors(poses, reference)
        assert errors.lateral_m == pytest.approx([0.1, -0.05])
        assert errors.heading_rad == pytest.approx([0.2, -0.1])
        assert errors.distance_m == pytest.approx([0.0, math.hypot(1.0, 0.15)])

    def test_a_route_that_comes_back_is_measured_against_the_right_pass(self) -> None:
        # East along y = 0, a U-turn, west along y = 0.4 (0.1 m steps). Both passes'
        # samples lie nearer the other pass; progress along the route picks the right one.
        xs = np.arange(0.0, 2.01, 0.1)
        out = np.column_stack([xs, np.zeros_like(xs), np.zeros_like(xs)])
        turn = np.array([[2.2, 0.2, math.pi / 2]])
        back = np.column_stack([xs[::-1], np.full_like(xs, 0.4), np.full_like(xs, math.pi)])
        reference = np.vstack([out, turn, back])
        shift = np.array([0.0, 0.25, 0.0])
        poses = np.vstack([out + shift, [[2.2, 0.2, math.pi / 2]], back - shift])
        errors = track_errors(poses, reference)
        k = len(xs) - 6  # away from the turn (the search window spans 8 segments)
        assert errors.lateral_m[:k] == pytest.approx(np.full(k, 0.25))
        assert errors.lateral_m[-k:] == pytest.approx(np.full(k, 0.25))
        assert errors.heading_rad[-k:] == pytest.approx(np.zeros(k), abs=1e-9)


def test_after_a_relocalization_samples_are_measured_against_the_new_plan() -> None:
    # Plan 1 runs east along y = 0 (key images 0-2); the robot is lost at x = 1 and
    # relocalizes onto plan 2, east along y = 1 (key images 10-12). Against plan 1
    # alone, the second block would be 1 m off.
    true_poses = {0: (0.0, 0.0, 0.0), 1: (1.0, 0.0, 0.0), 2: (2.0, 0.0, 0.0),
                  10: (0.0, 1.0, 0.0), 11: (1.0, 1.0, 0.0), 12: (2.0, 1.0, 0.0)}
    base = BaseState(odom_pose=(0.0, 0.0, 0.0), odom_distance_m=0.0, bumped=False,
                     stalled=False, battery_v=13.0, motors_enabled=True)

    def sample(t: int, state: MissionState, route: tuple[int, ...],
               pose: tuple[float, float, float]) -> CycleSample:
        record = CycleRecord(t_ns=t, state=state, base=base, follow=None, localization=None,
                             route=route, compute_ns=0)
        return CycleSample(record=record, pose_w=pose)

    following, lost = MissionState.FOLLOWING, MissionState.LOST
    samples = [sample(0, following, (0, 1, 2), (0.0, 0.02, 0.0)),
               sample(1, following, (0, 1, 2), (1.0, 0.02, 0.0)),
               sample(2, lost, (0, 1, 2), (1.0, 0.5, 0.0)),
               sample(3, following, (10, 11, 12), (1.0, 0.97, 0.0)),
               sample(4, following, (10, 11, 12), (2.0, 0.97, 0.0))]
    run = SimpleNamespace(samples=samples)
    taught = taught_paths(true_poses, [(0, 1, 2), (10, 11, 12)])
    errors = following_errors(run, taught)  # type: ignore[arg-type]
    assert errors is not None
    assert errors.lateral_m == pytest.approx([0.02, 0.02, -0.03, -0.03])
    assert errors.distance_m == pytest.approx([0.0, 1.0, 1.0, 2.0])
    assert len(plan_references(run, taught)) == 2  # type: ignore[arg-type]


def taught_paths(true_poses: dict[int, tuple[float, float, float]],
                 paths: list[tuple[int, ...]]) -> SimpleNamespace:
    """A taught memory's stand-in: true poses and paths of key image ids."""
    where = {k: SimpleNamespace(path_id=p, index=i)
             for p, ids in enumerate(paths) for i, k in enumerate(ids)}
    memory = SimpleNamespace(keyframe=where.__getitem__,
                             paths={p: SimpleNamespace(keyframe_ids=ids)
                                    for p, ids in enumerate(paths)})
    return SimpleNamespace(true_poses=true_poses, memory=memory)


def test_a_plan_made_between_two_key_images_is_measured_from_the_first() -> None:
    # Key images 0-3 run north along x = 0, 2 m apart; relocalized 1.5 m before key image
    # 2, on the taught path (3 cm beside it), the robot heads for 2: the plan is (2, 3).
    true_poses = {k: (0.0, 2.0 * k, math.pi / 2) for k in range(4)}
    base = BaseState(odom_pose=(0.0, 0.0, 0.0), odom_distance_m=0.0, bumped=False,
                     stalled=False, battery_v=13.0, motors_enabled=True)
    samples = [CycleSample(record=CycleRecord(
        t_ns=t, state=MissionState.FOLLOWING, base=base, follow=None, localization=None,
        route=(2, 3), compute_ns=0), pose_w=(0.03, y, math.pi / 2))
        for t, y in enumerate((2.5, 3.0, 4.5))]
    taught = taught_paths(true_poses, [(0, 1, 2, 3)])
    errors = following_errors(SimpleNamespace(samples=samples), taught)  # type: ignore[arg-type]
    assert errors is not None
    assert errors.lateral_m == pytest.approx([-0.03, -0.03, -0.03])  # not 1.5 m, 1 m
    assert plan_references(SimpleNamespace(samples=samples), taught)[0][0] == pytest.approx(
        true_poses[1])  # type: ignore[arg-type]


def test_the_key_image_headed_for_is_named_from_the_targets_not_the_route() -> None:
    # Route 4, 5, 6 where 5 is a junction crossing merged with 6: target 1 is key image 6.
    from robot.control_law import Twist
    from robot.follower import FollowStep
    from tools.demo_cmd import _status

    base = BaseState(odom_pose=(0.0, 0.0, 0.0), odom_distance_m=0.0, bumped=False,
                     stalled=False, battery_v=13.0, motors_enabled=True)
    follow = FollowStep(t_ns=0, target_index=1, twist=Twist(0.2, 0.0), vision=None,
                        corners_xy=np.zeros((0, 2)), y_m=None, theta_rad=None, s_m=None,
                        switch=None, lost=None)
    sample = CycleSample(record=CycleRecord(
        t_ns=0, state=MissionState.FOLLOWING, base=base, follow=follow, localization=None,
        route=(4, 5, 6), compute_ns=0, targets=(4, 6)), pose_w=(0.0, 0.0, 0.0))
    assert sample.record.target_key == 6
    assert _status(sample).startswith("following to key image 6 (2 of 2)")


def test_the_summary_rounds_for_people() -> None:
    from tools.figures.demo_report import summary_text

    report = {"reached_goal": True, "goal_key_image": 66, "state": "arrived",
              "detail": "at goal key image 66", "key_images_reached": 35,
              "key_images_route": 35, "distance_m": 17.6703, "sim_time_s": 88.76,
              "wall_time_s": 35.5579, "settling_distance_m": 2.1568, "lateral_rms_m": 0.0181,
              "lateral_max_m": 0.0552, "heading_rms_deg": 0.8466,
              "final_position_error_m": 0.016, "mean_matches": 74.4014, "loop_ms_p50": 8.537,
              "loop_ms_p95": 10.8702, "lost_events": 0}
    text = summary_text(report)
    assert "35/35 key images, 17.67 m in 88.8 s simulated, 35.6 s wall" in text
    assert "lateral RMS 1.8 cm, max 5.5 cm; heading RMS 0.85 deg" in text
    assert "final position error 1.6 cm" in text and "8.5 ms median" in text
    failed = summary_text({**report, "reached_goal": False, "lateral_rms_m": None,
                           "mean_matches": None})
    assert "did NOT reach the goal" in failed and "lateral RMS" not in failed
    assert "n/a matches" in failed


@pytest.mark.slow
def test_the_video_is_h264_with_the_target_key_image(short_demo, tmp_path) -> None:
    """On a copy of the short demo's memory, to key image 5 of ``east_a``: ``demo.mp4`` in H.264
    (browsers play it)."""
    import imageio_ffmpeg

    _, out, _ = short_demo
    copy = tmp_path / "seed1"
    copy.mkdir()
    shutil.copytree(out / "memory", copy / "memory")
    shutil.copy(out / "teach.json", copy / "teach.json")
    assert main(["demo", "--world", str(out.parent / "lab_short.toml"), "--routes",
                 "east_a,east_b", "--goal", "5", "--out", str(copy), "--no-log"]) == 0
    video = copy / "demo.mp4"
    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(video)],
                           capture_output=True, text=True, check=False).stderr
    assert re.search(r"Video: h264 .*yuv420p.*, 1200x600", probe), probe
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(video))
    report = json.loads((copy / "report.json").read_text())
    assert frames >= 0.8 * report["sim_time_s"] * 15 / VIDEO_EVERY  # minus the dispatch
