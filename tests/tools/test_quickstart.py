"""The README's quickstart, "Drive your own Pioneer", as a new user runs it: every command
of its steps 1 to 8, read from the README, in order, through a shell, against the simulator
standing in for the hardware (hardware in the loop).

``vmnav sim serve`` plays the Pioneer (on a serial pty, ``ttyUSB0`` in this test's folder)
and the camera (MJPEG over HTTP, its mount from the quickstart's ``vmnav.toml``). What
differs from the page, and nothing else:

* ``/dev/ttyUSB0`` is the pty, ``--camera 0`` the simulated camera's URL, ``ROBOT`` is
  ``127.0.0.1``, and the MAVLink port is a free one instead of 14550 (the robot is given
  ``--mavlink udpin:0.0.0.0:PORT``, its default with a key but for the port);
* ``--capture 0`` reads a video of a chessboard rendered through the simulated lens, so
  the calibration the robot then uses is one measured the way the page says;
* ``HOME`` is this test's folder (``~/vmnav`` is made by ``keygen``);
* ``drive`` gets its keys from a pseudo-terminal: four ``w`` (0.8 of full speed), then
  space and ``q`` once the simulator's truth says the robot went :data:`DRIVE_M`;
* ``door.jpg`` is the simulated camera's view at the end of that drive, and before step 7
  the simulator's hand carries the robot back to where teaching started;
* step 8's "stop the robot (Ctrl-C)" is a SIGINT to the robot's process (what a
  terminal's Ctrl-C sends to its foreground process).
"""

from __future__ import annotations

import json
import math
import os
import pty
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from shared.camera_model import CameraModel
from shared.logs.reader import log_info, read_messages
from shared.memory import read_memory
from tests.tools.board_video import board_video, render_board_views
from tests.tools.processes import start, wait_for

README = Path(__file__).resolve().parents[2] / "README.md"
#: Driven while teaching, m (the goal of step 7, key image 5, lies 1 to 2 m in; the
#: photo, taken at the end, well beyond it).
DRIVE_M = 3.0
#: Longest a step may take, s: only a hang (a loaded machine runs the robot slowly).
STEP_TIMEOUT_S = 240.0


def quickstart() -> tuple[str, list[str]]:
    """The quickstart's ``vmnav.toml`` and its shell commands in order (continuation
    lines joined, comments dropped)."""
    text = README.read_text()
    section = text[text.index("## Drive your own Pioneer"):text.index("**No robot yet?**")]
    blocks = re.findall(r"```(\w+)\n(.*?)```", section, re.S)
    (toml,) = [body for lang, body in blocks if lang == "toml"]
    commands = []
    for lang, body in blocks:
        if lang == "sh":
            joined = re.sub(r"\\\n\s*", "", body)
            commands += [line.split(" #")[0].strip() for line in joined.splitlines()
                         if line.strip()]
    return "\n".join(line.strip() for line in toml.splitlines()), commands


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Simulator:
    """``vmnav sim serve`` as the robot's hardware: its pty, camera and control endpoint."""

    def __init__(self, folder: Path) -> None:
        self.out = folder / "sim.out"
        self.process = start(["sim", "serve", "--config", str(folder / "vmnav.toml"),
                              "--aria", f"pty:{folder}/ttyUSB0", "--video", "http:0",
                              "--control", "http:0", "--route-start", "corridor"], self.out)
        self.camera = wait_for(r"camera on (\S+/stream\.mjpg)", self.out, self.process).group(1)
        self.control = wait_for(r"control on (\S+) ", self.out, self.process).group(1)

    def pose(self) -> list[float]:
        with urllib.request.urlopen(self.control + "/truth", timeout=10) as reply:
            return json.loads(reply.read())["pose_w"]

    def place(self, pose_w: list[float]) -> None:
        request = urllib.request.Request(self.control + "/place", method="POST",
                                         data=json.dumps({"pose_w": pose_w}).encode(),
                                         headers={"Content-Type": "application/json"})
        urllib.request.urlopen(request, timeout=10).close()

    def photo(self, path: Path) -> None:
        snapshot = self.camera.replace("stream.mjpg", "snapshot.jpg")
        with urllib.request.urlopen(snapshot, timeout=10) as reply:
            path.write_bytes(reply.read())


class User:
    """Runs the page's commands through ``bash`` in the user's folder, ``HOME`` set."""

    def __init__(self, folder: Path, sim: Simulator, port: int) -> None:
        self.folder, self.sim, self.port = folder, sim, port
        self.env = {**os.environ, "HOME": str(folder),
                    "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}"}

    def typed(self, command: str) -> str:
        """The command with the stand-ins of the module docstring."""
        command = (command.replace("/dev/ttyUSB0", f"{self.folder}/ttyUSB0")
                   .replace("--capture 0", f"--capture {self.folder}/boards.avi")
                   .replace("--camera 0", f"--camera {self.sim.camera}")
                   .replace("ROBOT:14550", f"127.0.0.1:{self.port}"))
        if command.startswith("vmnav robot "):
            command += f" --mavlink udpin:0.0.0.0:{self.port}"
        return command

    def run(self, command: str) -> str:
        """Run to the end; its output (exit status 0 and no traceback asserted)."""
        done = subprocess.run(["bash", "-c", command], cwd=self.folder, env=self.env,
                              capture_output=True, text=True, timeout=STEP_TIMEOUT_S)
        output = done.stdout + done.stderr
        assert done.returncode == 0 and "Traceback" not in output, f"$ {command}\n{output}"
        return output

    def start(self, command: str, out: Path) -> subprocess.Popen[bytes]:
        """Start a command that runs until stopped (the robot), its output in ``out``."""
        with out.open("wb") as sink:
            return subprocess.Popen(["bash", "-c", f"exec {command}"], cwd=self.folder,
                                    env=self.env, stdout=sink, stderr=subprocess.STDOUT)

    def drive(self, command: str) -> str:
        """``drive`` from a terminal: speed up, wait until :data:`DRIVE_M` driven, stop, quit."""
        master, slave = pty.openpty()
        process = subprocess.Popen(["bash", "-c", command], cwd=self.folder, env=self.env,
                                   stdin=slave, stdout=slave, stderr=slave)
        os.close(slave)
        output = b""
        try:
            while b"forward +0.0" not in output:  # keys are read from now on
                chunk = os.read(master, 4096)
                assert chunk, output
                output += chunk
            start_xy = self.sim.pose()[:2]
            os.write(master, b"wwww")
            limit = time.monotonic() + STEP_TIMEOUT_S
            while math.dist(self.sim.pose()[:2], start_xy) < DRIVE_M:
                assert process.poll() is None and time.monotonic() < limit, self.sim.pose()
                time.sleep(0.2)
            os.write(master, b" q")
            assert process.wait(30) == 0
            while True:
                try:
                    chunk = os.read(master, 4096)
                except OSError:  # the other end closed
                    break
                if not chunk:
                    break
                output += chunk
        finally:
            if process.poll() is None:
                process.kill()
            os.close(master)
        return output.decode(errors="replace")


def step(command: str) -> str:
    """What a command does, to name its output: ``vmnav ground --key K --connect A goto 8``
    -> ``ground goto 8``."""
    return re.sub(r"^vmnav (ground) (--\S+ \S+ )*|^vmnav ", r"\1 ", command).strip()


@pytest.mark.slow
def test_the_quickstart_runs_in_order_against_the_simulator(tmp_path: Path) -> None:
    toml, commands = quickstart()
    assert [step(c) for c in commands] == [
        "pioneer --aria serial:/dev/ttyUSB0",
        "pioneer --aria serial:/dev/ttyUSB0 --drive 0.1 0 --duration 2",
        "calibrate --capture 0 --views calib_views --pattern 9x6 --square 0.025 -o camera.json",
        "ground keygen ~/vmnav/vmnav.key",
        "robot --aria serial:/dev/ttyUSB0 --camera 0 --calibration camera.json --config "
        "vmnav.toml --key ~/vmnav/vmnav.key --memory ~/vmnav/memory",
        "ground teach start corridor", "ground drive", "ground teach stop",
        "ground memory list", "ground goto 5 --wait", "ground goto --image door.jpg --wait",
        "ground stop", "ground arm", "log info logs/robot-0001.mcap",
        "log plot logs/robot-0001.mcap"]
    (tmp_path / "vmnav.toml").write_text(toml)
    board_video(tmp_path / "boards.avi",
                render_board_views(tmp_path / "rendered", CameraModel.default(), 20))
    sim = Simulator(tmp_path)
    user = User(tmp_path, sim, free_udp_port())
    robot: subprocess.Popen[bytes] | None = None
    said: dict[str, str] = {}
    poses: dict[str, list[float]] = {}
    signalled_ns: int | None = None  # when step 8 stopped the robot, on its clock
    try:
        for command in commands:
            typed, name = user.typed(command), step(command)
            if name.startswith("robot"):
                robot = user.start(typed, tmp_path / "robot.out")
                wait_for(r"vmnav robot: .* MAVLink system 1 on udpin:0\.0\.0\.0:\d+ \(signed\)",
                         tmp_path / "robot.out", robot, STEP_TIMEOUT_S)
                continue
            if name == "ground drive":
                said[name] = user.drive(typed)
                sim.photo(tmp_path / "door.jpg")
                poses["photo"] = sim.pose()
                continue
            if name.startswith("ground teach start"):
                poses["teach"] = sim.pose()
            if name == "ground memory list":  # "drive the robot back near the start"
                sim.place(poses["teach"])
            if name.startswith("log") and robot is not None and robot.poll() is None:
                signalled_ns = time.monotonic_ns()  # the robot's WallClock: the same clock
                robot.send_signal(signal.SIGINT)  # "stop the robot (Ctrl-C)"
                assert robot.wait(STEP_TIMEOUT_S) == 130
            said[name] = user.run(typed)
            poses[name] = sim.pose()
    finally:
        if robot is not None:
            robot.terminate()
            robot.wait(30)
        sim.process.terminate()
        sim.process.wait(30)
    robot_out = (tmp_path / "robot.out").read_text()
    assert "Traceback" not in robot_out, robot_out
    assert "pioneer: Closed()" in robot_out, robot_out
    assert "vmnav robot: stopped by SIGINT; base stopped, links closed" in robot_out, robot_out
    assert "connected to 'vmnav'" in said["pioneer --aria serial:/dev/ttyUSB0"]
    assert "wrote camera.json" in said[step(commands[2])]
    assert (tmp_path / "vmnav" / "vmnav.key").stat().st_mode & 0o777 == 0o600
    assert "teaching 'corridor'" in said["ground teach start corridor"]
    assert "forward +0.8" in said["ground drive"]
    memory = read_memory(tmp_path / "vmnav" / "memory")
    (path,) = memory.paths.values()
    assert path.name == "corridor" and 5 in path.keyframe_ids
    assert f"path {path.id} stored" in said["ground teach stop"]
    assert said["ground memory list"].startswith(f"path {path.id} 'corridor': key images ")
    # Arrived where key image 5 was taught, then where the key image the photo was found
    # at was taught (straight east), near where the photo was taken.
    found = int(re.search(r"found at key image (\d+)",
                          said["ground goto --image door.jpg --wait"]).group(1))
    assert abs(poses["teach"][0] + memory.keyframes[found].distance_m - poses["photo"][0]) < 0.5
    for name, goal_x in (("ground goto 5 --wait", poses["teach"][0]
                          + memory.keyframes[5].distance_m),
                         ("ground goto --image door.jpg --wait", poses["teach"][0]
                          + memory.keyframes[found].distance_m)):
        assert "goal reached" in said[name], said[name]
        assert abs(poses[name][0] - goal_x) < 0.15 and abs(poses[name][1] - 10.0) < 0.1, \
            (name, poses[name], goal_x)
    assert "emergency stop accepted" in said["ground stop"]
    assert "armed" in said["ground arm"]
    assert "status    complete" in said["log info logs/robot-0001.mcap"]
    field_log = tmp_path / "logs" / "robot-0001.mcap"
    info = log_info(field_log)  # its start in Unix time, as Foxglove and `mcap info` read it
    assert info.start_ns is not None and info.unix_offset_ns is not None
    assert abs(info.start_ns / 1e9 - time.time()) < 3600
    assert {"/camera/image/compressed", "/tf", "/pioneer/sip", "/mavlink/in/MANUAL_CONTROL",
            "/mavlink/out/HEARTBEAT", "/log"} <= {t.topic for t in info.topics}
    # The log was finished after the driver closed (stop and CLOSE sent): its last line,
    # written then, gives the driver's last SIP, and that SIP is the log's last.
    *_, closed = read_messages(field_log, ["/log"])
    *_, last_sip = read_messages(field_log, ["/pioneer/sip"])
    gap_ms = (closed.log_time_ns - last_sip.log_time_ns) / 1e6
    assert signalled_ns is not None and closed.clock_ns > signalled_ns
    assert closed.data["name"] == "robot.pioneer"
    assert closed.data["message"].startswith("pioneer closed: "), closed.data
    assert f"SIPs (the last {gap_ms:.1f} ms before)" in closed.data["message"], closed.data
    assert "wrote logs/robot-0001-matches.png" in said["log plot logs/robot-0001.mcap"]
