"""Stock MAVProxy drives the real robot: ``wp load`` of a one-goal mission then ``mode AUTO``,
against ``vmnav robot`` on ``vmnav sim serve`` (ARIA over TCP, camera over HTTP), with a
copy of the session's memory of ``east_a`` (tests/conftest.py). The robot must arrive at the
goal, as the simulator's truth says."""

from __future__ import annotations

import json
import shutil
import signal
import socket
import urllib.request

import pytest

from shared.mavlink.dialect import mavlink
from shared.memory import read_memory
from tests.robot.vehicle.mavproxy_console import MavproxyConsole
from tests.tools.processes import start, wait_for

pytest.importorskip("MAVProxy", reason="stock MAVProxy is not installed")



def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.slow
def test_wp_load_then_mode_auto_drives_the_robot_to_the_goal(east_a, tmp_path) -> None:
    world, memory = east_a
    shutil.copytree(memory, tmp_path / "memory")
    goal = read_memory(tmp_path / "memory").paths[0].keyframe_ids[-1]
    sim_log, robot_log = tmp_path / "sim.out", tmp_path / "robot.out"
    sim = start(["sim", "serve", "--world", str(world), "--aria", "tcp:0", "--video", "http:0",
                 "--control", "http:0"], sim_log)
    processes = [sim]
    home = tmp_path / "mavproxy"
    home.mkdir()
    mavproxy = None
    try:
        aria = wait_for(r"ARIA on tcp (\S+)", sim_log, sim).group(1)
        camera = wait_for(r"camera on (\S+/stream\.mjpg)", sim_log, sim).group(1)
        control = wait_for(r"control on (\S+) ", sim_log, sim).group(1)
        port = free_udp_port()
        robot = start(["robot", "--aria", f"socket://{aria}", "--camera", camera,
                       "--mavlink", f"udpin:127.0.0.1:{port}", "--memory",
                       str(tmp_path / "memory"), "--state", str(tmp_path / "state"),
                       "--no-log"], robot_log)
        processes.append(robot)
        wait_for(r"vmnav robot: ", robot_log, robot)
        mavproxy = MavproxyConsole(f"udpout:127.0.0.1:{port}", home)
        mavproxy.expect(r"Mode HOLD", 0, timeout_s=30)
        item = [0, 1, mavlink.MAV_FRAME_MISSION, mavlink.MAV_CMD_WAYPOINT_USER_1, goal,
                0, 0, 0, 0, 0, 0, 1]
        mission = home / "goal.txt"
        mission.write_text("QGC WPL 110\n" + "\t".join(map(str, item)) + "\n")
        mavproxy.expect(r"Got MISSION_ACK: TYPE_MISSION: ACCEPTED",
                        mavproxy.send(f"wp load {mission}"))
        mark = mavproxy.send("mode AUTO")
        mavproxy.expect(r"Mode AUTO$", mark)
        mavproxy.expect(rf"AP: mission arrived: arrived: at goal key image {goal}", mark,
                        timeout_s=60)
        mavproxy.expect(r"Mode HOLD$", mark)
        with urllib.request.urlopen(control + "/truth", timeout=5) as reply:
            x, y, _ = json.loads(reply.read())["pose_w"]
        assert x == pytest.approx(4.5, abs=0.15) and y == pytest.approx(10.0, abs=0.1)
    finally:
        if mavproxy is not None:
            mavproxy.close()
        for process in reversed(processes):
            process.send_signal(signal.SIGTERM)
            process.wait(15)
