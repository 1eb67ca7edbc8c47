"""Stock MAVProxy (a subprocess, typed at through its stdin) against the vehicle running its own
I/O thread on the wall clock: mode names, ``param fetch``/``param set``, ``wp load`` of a goal
then ``mode AUTO``, ``ftp list``/``ftp get`` of a thumbnail. Effects are checked on the
vehicle's side (FakeApp calls, the parameter file, the served files), not only in MAVProxy's
words.

One MAVProxy serves the whole module (starting one costs about 3 s); each test starts with
FakeApp's call record empty, and only the mission test changes the vehicle's mode (MAVProxy
prints a mode name only when the HEARTBEAT's mode changes).
"""

from __future__ import annotations

import importlib.util
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from robot.vehicle.robot_params import ROBOT_PARAMS
from shared.clock import WallClock
from shared.mavlink.dialect import mavlink, to_float32
from shared.mavlink.mission.goal import GOAL_COMMAND, Goal
from shared.mavlink.modes import Mode
from shared.memory.store import thumbnail_path, write_memory
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle
from tests.robot.vehicle.mavproxy_console import MavproxyConsole, wait_until
from tests.shared.memory.builders import loop_memory

if importlib.util.find_spec("MAVProxy") is None:
    pytest.skip("MAVProxy is not installed (it comes with pip install -e '.[dev]')",
                allow_module_level=True)

#: What MAVProxy prints once it holds every parameter of the vehicle.
ALL_PARAMS = rf"Received {len(ROBOT_PARAMS)} parameters$"


@dataclass(frozen=True)
class Session:
    """The vehicle's files (under ``root``), its application and MAVProxy connected to it."""

    root: Path
    app: FakeApp
    console: MavproxyConsole


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Session]:
    """MAVProxy connected to the vehicle: it named the vehicle's mode from the HEARTBEAT and
    finished its start-up parameter download."""
    root = tmp_path_factory.mktemp("stock_mavproxy")
    app = FakeApp()
    vehicle = make_vehicle(root, app, WallClock())
    vehicle.start_thread()
    home = root / "mavproxy"
    home.mkdir()
    console = MavproxyConsole(f"udpout:127.0.0.1:{vehicle.link.local_port}", home)
    try:
        console.expect(r"Detected vehicle 1:1 on link 0")
        console.expect(r"Mode MANUAL$")
        console.expect(ALL_PARAMS)
        yield Session(root, app, console)
    finally:
        console.close()
        vehicle.close()


@pytest.fixture
def mavproxy(session: Session) -> MavproxyConsole:
    """The module's MAVProxy, FakeApp's call record emptied."""
    session.app.calls.clear()
    return session.console


@pytest.fixture
def app(session: Session) -> FakeApp:
    return session.app


@pytest.fixture
def root(session: Session) -> Path:
    return session.root


def test_param_fetch_then_set_is_applied_and_persisted(
        mavproxy: MavproxyConsole, app: FakeApp, root: Path) -> None:
    mavproxy.expect(ALL_PARAMS, mavproxy.send("param fetch"))
    shown = mavproxy.expect(r"CTL_SPEED\s+(\S+)$", mavproxy.send("param show CTL_SPEED"))
    assert float(shown[1]) == to_float32(0.2)  # the vehicle's default, fetched

    mavproxy.send("param set CTL_SPEED 0.3")
    wait_until(lambda: app.configs[-1].control.speed_m_s == to_float32(0.3),
               "the vehicle applies the new value")
    stored = json.loads((root / "params.json").read_text())  # written before it is applied
    assert stored["params"] == {"CTL_SPEED": to_float32(0.3)}
    # read back from the vehicle (``param show`` would race the echo into MAVProxy's cache)
    read = mavproxy.expect(r"CTL_SPEED = (\S+)$", mavproxy.send("param fetch CTL_SPEED"))
    assert float(read[1]) == pytest.approx(0.3)  # printed with 7 decimals


def test_wp_load_of_a_goal_then_mode_auto_starts_it(
        mavproxy: MavproxyConsole, app: FakeApp, root: Path) -> None:
    # QGC WPL 110: seq current frame command p1..p4 x y z autocontinue; p1 = key image id
    item = [0, 1, mavlink.MAV_FRAME_MISSION, GOAL_COMMAND, 3, 0, 0, 0, 0, 0, 0, 1]
    mission = root / "goal.txt"
    mission.write_text("QGC WPL 110\n" + "\t".join(map(str, item)) + "\n")

    mark = mavproxy.send(f"wp load {mission}")
    mavproxy.expect(r"Got MISSION_ACK: TYPE_MISSION: ACCEPTED", mark)
    assert app.called("validate_goals") == [((Goal(3),),)]

    mark = mavproxy.send("mode AUTO")
    mavproxy.expect(r"Got COMMAND_ACK: DO_SET_MODE: ACCEPTED", mark)
    mavproxy.expect(r"AP: mission localizing", mark)  # the vehicle's STATUSTEXT
    mavproxy.expect(r"Mode AUTO$", mark)  # decoded from the vehicle's HEARTBEAT
    assert app.called("start_mission") == [((Goal(3),), 0)]

    mark = mavproxy.send("mode HOLD")
    mavproxy.expect(r"Mode HOLD$", mark)
    assert app.called("set_mode") == [(Mode.HOLD,)]


def test_ftp_list_and_get_of_a_thumbnail(mavproxy: MavproxyConsole, root: Path,
                                         rng: np.random.Generator) -> None:
    memory_dir = root / "memory"
    write_memory(memory_dir, loop_memory(rng))

    mark = mavproxy.send("ftp list /memory/thumbnails")
    listing = mavproxy.lines_between(mark, r"Total size")
    listed = dict(re.findall(r"^\s+(\S+)\t(\d+)$", "\n".join(listing), re.MULTILINE))
    on_disk = {p.name: str(p.stat().st_size) for p in (memory_dir / "thumbnails").iterdir()}
    assert listed == on_disk and len(on_disk) > 1

    got, expected = root / "got.png", thumbnail_path(memory_dir, 5).read_bytes()
    mark = mavproxy.send(f"ftp get /memory/thumbnails/5.png {got}")
    assert int(mavproxy.expect(r"Wrote (\d+) bytes", mark)[1]) == len(expected)
    # MAVProxy prints that before it closes (and so flushes) the file
    wait_until(lambda: got.stat().st_size == len(expected), "MAVProxy closes the file")
    assert got.read_bytes() == expected
