"""``vmnav robot`` as the field runs it: its parts on real transports, and what it says
when one of them is wrong.

``vmnav sim serve`` is the emulated Pioneer on TCP and the camera as MJPEG over HTTP;
``vmnav robot`` connects to both and to this test's ground station. Teaching by
teleoperation and the stop by a signal, with the field log that records them, are the
README quickstart's test (``tests/tools/test_quickstart.py``)."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import time

import pytest

from ground.station import GroundStation
from shared.calibration import write_camera
from shared.camera_model import CameraModel
from shared.clock import WallClock
from shared.key_file import read_key_file
from shared.memory import write_memory
from tests.robot.vehicle.stream_rig import Radios
from tests.shared.memory.builders import folder_bytes, loop_memory, memory_without_manifest
from tests.tools.processes import VMNAV, start, wait_for


@pytest.fixture
def sim_serve(tmp_path):
    log = tmp_path / "sim.out"
    process = start(["sim", "serve", "--aria", "tcp:0", "--video", "http:0"], log)
    try:
        aria = wait_for(r"ARIA on tcp 127\.0\.0\.1:(\d+)", log, process).group(1)
        camera = wait_for(r"camera on (http://\S+/stream\.mjpg)", log, process).group(1)
        yield f"tcp:127.0.0.1:{aria}", camera
    finally:
        process.send_signal(signal.SIGTERM)
        process.wait(10)


@pytest.mark.slow
def test_a_missing_camera_is_one_line_at_start(sim_serve, tmp_path) -> None:
    aria, _ = sim_serve
    result = subprocess.run(
        [*VMNAV, "robot", "--aria", aria, "--camera", str(tmp_path / "none.mp4"),
         "--memory", str(tmp_path / "memory")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].endswith(
        "none.mp4: no such video file (nor a device index or URL)")


def run_robot(*args: str, timeout_s: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*VMNAV, "robot", *args], capture_output=True, text=True,
                          timeout=timeout_s)


@pytest.mark.slow
def test_a_memory_folder_without_its_manifest_is_one_line_at_start(tmp_path, rng) -> None:
    memory = tmp_path / "memory"
    before = memory_without_manifest(memory, rng)
    # Refused before the Pioneer or the camera is opened (neither exists here).
    result = run_robot("--aria", "socket://127.0.0.1:9", "--camera", str(tmp_path / "none.mp4"),
                       "--memory", str(memory), "--log", str(tmp_path / "logs"))
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"vmnav robot: error: memory {memory}: manifest.json missing but the folder holds 21 "
        "files; restore it or point --memory to an empty folder"]
    assert folder_bytes(memory) == before
    assert not (tmp_path / "logs").exists()


def test_a_calibration_of_another_camera_than_the_memorys_is_one_line_at_start(
        tmp_path, rng) -> None:
    memory = tmp_path / "memory"
    write_memory(memory, loop_memory(rng))  # a small camera
    before = folder_bytes(memory)
    calibration = tmp_path / "camera.json"
    write_camera(calibration, CameraModel.default())
    result = run_robot("--aria", "socket://127.0.0.1:9", "--camera", str(tmp_path / "none.mp4"),
                       "--memory", str(memory), "--calibration", str(calibration), "--no-log")
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"vmnav robot: error: {memory}: holds a memory taught with another camera than the "
        "one given"]
    assert folder_bytes(memory) == before


@pytest.mark.slow
def test_wrong_urls_and_ports_in_use_are_one_line_at_start(sim_serve, tmp_path) -> None:
    aria, camera = sim_serve
    memory = ["--memory", str(tmp_path / "memory"), "--no-log"]
    bad_camera = run_robot("--aria", aria, "--camera", camera.replace("stream", "nothing"),
                           *memory)
    assert bad_camera.returncode == 1
    assert "nothing.mjpg: cannot open with OpenCV" in bad_camera.stderr.splitlines()[-1]
    assert bad_camera.stderr.count("\n") == 1, bad_camera.stderr  # no OpenCV/FFmpeg warnings
    started = time.monotonic()
    no_robot = run_robot("--aria", "tcp:127.0.0.1:9", "--camera", camera, *memory)
    assert no_robot.returncode == 1 and time.monotonic() - started < 30
    assert no_robot.stderr.splitlines()[-1] == (
        "vmnav robot: error: --aria tcp:127.0.0.1:9: cannot connect to 127.0.0.1:9: "
        "Connection refused")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        in_use = run_robot("--aria", aria, "--camera", camera, "--mavlink",
                           f"udpin:127.0.0.1:{port}", *memory)
    assert in_use.returncode == 1
    assert f"udpin:127.0.0.1:{port}" in in_use.stderr.splitlines()[-1]
    with socket.socket() as taken_tcp:
        taken_tcp.bind(("127.0.0.1", 0))
        taken_tcp.listen(1)
        port = taken_tcp.getsockname()[1]
        video_in_use = run_robot("--aria", aria, "--camera", camera, "--video",
                                 f"http:127.0.0.1:{port}", *memory)
        foxglove_in_use = run_robot("--aria", aria, "--camera", camera, "--foxglove",
                                    str(port), *memory)
    assert video_in_use.returncode == 1
    assert f"http:127.0.0.1:{port}: cannot listen" in video_in_use.stderr.splitlines()[-1]
    assert foxglove_in_use.returncode == 1
    assert foxglove_in_use.stderr.splitlines() == [
        f"vmnav robot: error: --foxglove {port}: cannot listen: Failed to bind port: Address "
        "already in use (os error 98)"]  # before the Pioneer was connected: nothing from it
    assert "Traceback" not in (bad_camera.stderr + no_robot.stderr + in_use.stderr
                               + video_in_use.stderr)


def test_a_bad_video_spec_is_one_line_before_anything_opens(tmp_path) -> None:
    memory = tmp_path / "memory"
    result = run_robot("--aria", "socket://127.0.0.1:9", "--camera", str(tmp_path / "none.mp4"),
                       "--memory", str(memory), "--video", "rtsp:8554", "--no-log")
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines() == [
        "vmnav robot: error: --video: 'rtsp:8554' is not http:PORT or http:HOST:PORT"]
    assert not memory.exists()


def test_an_unsigned_link_open_to_the_network_is_refused_at_start(tmp_path) -> None:
    memory = tmp_path / "memory"
    result = run_robot("--aria", "socket://127.0.0.1:9", "--camera", str(tmp_path / "none.mp4"),
                       "--memory", str(memory), "--mavlink", "udpin:0.0.0.0:14550", "--no-log")
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines() == [
        "vmnav robot: error: --mavlink udpin:0.0.0.0:14550: an unsigned link open to the "
        "network lets anyone drive the robot: make a key with `vmnav ground keygen FILE` and "
        "give it to both ends (--key FILE), or add --insecure"]
    assert not memory.exists()  # refused before anything was opened


@pytest.mark.slow
def test_a_signed_robot_talks_only_to_its_key_and_keeps_its_timestamps(
        sim_serve, tmp_path) -> None:
    aria, camera = sim_serve
    key = tmp_path / "vmnav.key"
    assert subprocess.run([*VMNAV, "ground", "keygen", str(key)], timeout=60).returncode == 0
    clock = WallClock()
    with GroundStation.open("udpin:127.0.0.1:0", clock, key=read_key_file(key),
                            unix_offset_ns=time.time_ns() - clock.now_ns()) as station:
        log = tmp_path / "robot.out"
        robot = start(["robot", "--aria", aria, "--camera", camera, "--key", str(key),
                       "--mavlink", f"udpout:127.0.0.1:{station.link.local_port}",
                       "--memory", str(tmp_path / "memory"), "--state", str(tmp_path / "state"),
                       "--no-log"], log)
        try:
            station.wait_vehicle(30.0)
            assert station.set_param("CTL_SPEED", 0.15) == pytest.approx(0.15)
        finally:
            robot.send_signal(signal.SIGTERM)
            code = robot.wait(15)
    output = log.read_text()
    assert code == 143 and "Traceback" not in output, output
    assert f"on udpout:127.0.0.1:{station.link.local_port} (signed)" in output
    assert station.codec.signing.badsig_count == 0 and station.codec.signing.goodsig_count > 0
    kept = json.loads((tmp_path / "state" / "signing-timestamps.json").read_text())
    assert [stream[:3] for stream in kept["streams"]] == [[1, 255, 190]]  # ours, link 1


@pytest.mark.slow
def test_the_ground_over_tcp_and_the_old_aria_url(sim_serve, tmp_path) -> None:
    """``vmnav robot --aria socket://... --mavlink tcpin:...``, ``vmnav ground --connect
    tcp:...``: the robot takes the old ARIA form and a ground station over TCP."""
    aria, camera = sim_serve
    log = tmp_path / "robot.out"
    robot = start(["robot", "--aria", aria.replace("tcp:", "socket://"), "--camera", camera,
                   "--mavlink", "tcpin:127.0.0.1:0", "--memory", str(tmp_path / "memory"),
                   "--state", str(tmp_path / "state"), "--no-log"], log)
    try:
        port = wait_for(r"MAVLink system 1 on tcpin:127\.0\.0\.1:(\d+)", log, robot).group(1)
        status = subprocess.run([*VMNAV, "ground", "--connect", f"tcp:127.0.0.1:{port}",
                                 "--timeout", "20", "status"],
                                capture_output=True, text=True, timeout=60)
        assert status.returncode == 0, status.stderr
        assert status.stdout.startswith("vehicle 1: mode HOLD, "), status.stdout
    finally:
        robot.send_signal(signal.SIGTERM)
        robot.wait(15)
    assert "Traceback" not in log.read_text()


@pytest.mark.parametrize(("args", "line"), [
    (["--mavlink", "tcp:5760"],
     "--mavlink: 'tcp:5760': expected tcp:HOST:PORT (a host and a port)"),
    (["--mavlink", "tcpin:0.0.0.0:5760"],
     "--mavlink tcpin:0.0.0.0:5760: an unsigned link open to the network"),
    (["--mavlink", "serial:/dev/ttyNOPE:57600"], "/dev/ttyNOPE: no such device"),
    (["--aria", "udpin:127.0.0.1:8101"], "--aria: 'udpin:127.0.0.1:8101': udpin:HOST:PORT "
                                         "cannot be used here"),
])
def test_bad_links_are_one_line_before_anything_starts(tmp_path, args, line) -> None:
    memory = tmp_path / "memory"
    result = run_robot("--camera", str(tmp_path / "none.mp4"), "--memory", str(memory),
                       "--no-log", *(["--aria", "tcp:127.0.0.1:9"] if "--aria" not in args
                                     else []), *args)
    assert result.returncode == 1, result.stderr
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("vmnav robot: error: ") and line in last, result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.slow
def test_the_ground_over_a_radio_pair_and_the_pioneer_on_a_serial_port(tmp_path) -> None:
    """docs/links.md: ``vmnav robot --aria serial:DEVICE --mavlink serial:RADIO:57600`` and
    ``vmnav ground --connect serial:RADIO:57600 --key KEY status``, the Pioneer being
    ``vmnav sim serve --aria pty:PATH`` and the radios two ptys joined by a relay."""
    key = tmp_path / "vmnav.key"
    assert subprocess.run([*VMNAV, "ground", "keygen", str(key)], timeout=60).returncode == 0
    pioneer = tmp_path / "pioneer"
    sim_log, robot_log = tmp_path / "sim.out", tmp_path / "robot.out"
    sim = start(["sim", "serve", "--aria", f"pty:{pioneer}", "--video", "http:0"], sim_log)
    radios = Radios(tmp_path)
    robot = None
    try:
        camera = wait_for(r"camera on (http://\S+/stream\.mjpg)", sim_log, sim).group(1)
        robot = start(["robot", "--aria", f"serial:{pioneer}", "--camera", camera,
                       "--mavlink", f"serial:{radios.robot_path}:57600", "--key", str(key),
                       "--memory", str(tmp_path / "memory"), "--state", str(tmp_path / "state"),
                       "--no-log"], robot_log)
        wait_for(r"MAVLink system 1 on serial:", robot_log, robot)
        status = subprocess.run([*VMNAV, "ground", "--connect",
                                 f"serial:{radios.ground_path}:57600", "--key", str(key),
                                 "--timeout", "20", "status"],
                                capture_output=True, text=True, timeout=60)
        assert status.returncode == 0, status.stderr
        assert status.stdout.startswith("vehicle 1: mode HOLD, "), status.stdout
    finally:
        for process in (robot, sim):
            if process is not None:
                process.send_signal(signal.SIGTERM)
                process.wait(15)
        radios.close()
    assert "Traceback" not in robot_log.read_text()
