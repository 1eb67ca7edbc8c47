"""``vmnav log dump``: pymavlink's mavlogdump decodes every vmnav message of a ground tlog
by name, where the stock ``mavlogdump.py`` shows ``UNKNOWN_<id>``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from ground.ground_log import GroundLog
from ground.tlog_dump import VMNAV_IDS
from shared.clock import ManualClock
from shared.config import LogConfig
from shared.mavlink.dialect import Message, make_codec, mavlink

ROOT = Path(__file__).resolve().parents[2]
S = 1_000_000_000
#: 2025-11-14 16:00:00 UTC, ns.
UNIX_NS = 1_763_136_000 * S
#: One value per MAVLink base type, each exact in float32 and in every integer type.
VALUES = {"char": "v", "float": 0.5, "double": 0.25}


def vmnav_messages() -> list[Message]:
    """One message of every vmnav message type (ids 24400-24499), from the dialect itself,
    with each field set to a value that survives the wire exactly."""
    messages = []
    for msg_id, cls in sorted(mavlink.mavlink_map.items()):
        if msg_id not in VMNAV_IDS:
            continue
        args = []
        for name, length in zip(cls.fieldnames, cls.array_lengths, strict=True):
            base = cls.fieldtypes[cls.fieldnames.index(name)].removesuffix("_t")
            value = VALUES.get(base, 3)
            args.append("v" * length if base == "char" and length else
                        [value] * length if length else value)
        messages.append(cls(*args))
    assert messages, "the dialect has no message in 24400-24499"
    return messages


@pytest.fixture(scope="module")
def tlog(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Message]]:
    """A ground tlog written by the ground log: a HEARTBEAT then each vmnav message, as
    the robot (system 1) would send them."""
    folder = tmp_path_factory.mktemp("tlog")
    robot = make_codec(1, 1)
    sent = [mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GROUND_ROVER,
                                              mavlink.MAV_AUTOPILOT_GENERIC, 0, 0, 4, 3),
            *vmnav_messages()]
    ground_log = GroundLog(LogConfig(output_dir=str(folder)), ManualClock(), UNIX_NS)
    for i, msg in enumerate(sent):
        ground_log.record("in", robot.pack(msg), msg, i * S // 10)
    ground_log.close()
    return ground_log.tlog.path, sent


def run(*argv: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.run(argv, capture_output=True, text=True, env=env, timeout=120, cwd=ROOT)


def test_the_stock_mavlogdump_does_not_know_our_messages(tlog) -> None:
    path, sent = tlog
    stock = Path(sys.executable).parent / "mavlogdump.py"
    if not stock.exists():
        pytest.skip(f"no {stock}")
    done = run(sys.executable, str(stock), str(path))
    assert done.returncode == 0, done.stderr
    assert f"UNKNOWN_{sent[1].get_msgId()}" in done.stdout


def test_vmnav_log_dump_decodes_every_vmnav_message_by_name(tlog) -> None:
    path, sent = tlog
    done = run(sys.executable, "-m", "tools.cli", "log", "dump", str(path), "--format", "json")
    assert (done.returncode, done.stderr) == (0, "")
    dumped = [json.loads(line) for line in done.stdout.splitlines()]
    assert [d["meta"]["type"] for d in dumped] == [m.get_type() for m in sent]
    assert not any(d["meta"]["type"].startswith("UNKNOWN") for d in dumped)
    for d, msg in zip(dumped, sent, strict=True):
        assert d["data"] == {name: getattr(msg, name) for name in msg.fieldnames}, msg
    # The tlog's Unix times, as the ground log wrote them.
    assert dumped[0]["meta"]["timestamp"] == pytest.approx(UNIX_NS / S)


def test_mavlogdump_options_pass_through(tlog) -> None:
    path, _ = tlog
    done = run(sys.executable, "-m", "tools.cli", "log", "dump", str(path), "--types",
               "VISUAL_SERVO_STATUS")
    assert done.returncode == 0, done.stderr
    [line] = done.stdout.splitlines()
    assert "VISUAL_SERVO_STATUS {time_usec : 3, " in line


def test_a_missing_tlog_is_one_line(tmp_path: Path) -> None:
    done = run(sys.executable, "-m", "tools.cli", "log", "dump", str(tmp_path / "no.tlog"))
    assert (done.returncode, done.stdout) == (1, "")
    assert done.stderr == f"vmnav log: error: {tmp_path / 'no.tlog'}: no such file\n"
