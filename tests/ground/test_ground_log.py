"""The ground log: ``vmnav ground --log DIR`` against a real vehicle endpoint, and the tlog
file on its own (record layout, flushing, naming, errors)."""

from __future__ import annotations

import base64
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import pytest
from mcap.reader import make_reader

from ground.ground_log import GroundLog, Tlog, create_tlog, tlog_record
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import ManualClock
from shared.config import LogConfig
from shared.errors import InputError
from shared.logs import topics
from shared.logs.reader import log_info, read_messages, read_metadata
from shared.mavlink.dialect import make_codec, mavlink
from tests.ground.conftest import run_ground

S = 1_000_000_000
#: 2026-11-21 15:22:37 UTC, ns.
UNIX_NS = 1_795_274_557 * S


def read_tlog(path: Path) -> list[tuple[float, int, str, bytes]]:
    """(time s, source system, message name, frame) per message, by pymavlink's tlog reader."""
    from pymavlink import mavutil

    log = mavutil.mavlink_connection(str(path))
    try:
        out = []
        while (msg := log.recv_match()) is not None:
            if msg.get_type() != "BAD_DATA":
                out.append((msg._timestamp, msg.get_srcSystem(), msg.get_type(),
                            bytes(msg.get_msgbuf())))
        return out
    finally:
        log.close()


def test_ground_log_holds_every_packet_in_both_files(vehicle: UdpVehicle, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "logs"
    start_s = time.time()
    assert run_ground(vehicle, "--log", str(folder), "params", "list") == 0
    end_s = time.time()
    [mcap] = folder.glob("ground-*.mcap")
    [tlog] = folder.glob("ground-*.tlog")
    assert mcap.name == "ground-0001.mcap"
    assert tlog.name in {f"ground-{time.strftime('%Y%m%d-%H%M%S', time.gmtime(t))}.tlog"
                         for t in (start_s, end_s)}
    err = capsys.readouterr().err
    assert err.startswith("vmnav ground: logged ") and str(mcap) in err and str(tlog) in err

    records = read_tlog(tlog)
    times = [t for t, _, _, _ in records]
    assert times == sorted(times) and start_s - 0.1 <= times[0] and times[-1] <= end_s + 0.1
    kinds = Counter((system, name) for _, system, name, _ in records)
    assert kinds[(1, "HEARTBEAT")] >= 1 and kinds[(255, "HEARTBEAT")] >= 1
    assert kinds[(255, "PARAM_REQUEST_LIST")] >= 1 and kinds[(1, "PARAM_VALUE")] >= 10

    info = log_info(mcap)
    assert info.complete
    counts = {t.topic: t.message_count for t in info.topics}
    for direction in topics.MAVLINK_DIRECTIONS:
        assert counts[topics.mavlink_topic(direction, "HEARTBEAT")] >= 1
    assert counts[topics.mavlink_topic("in", "PARAM_VALUE")] == kinds[(1, "PARAM_VALUE")]
    raw = [m.data for m in read_messages(mcap, [topics.MAVLINK_RAW])]
    assert {r["direction"] for r in raw} == {"in", "out"}
    # The same frames, byte for byte, in both files.
    assert Counter(base64.b64decode(r["frame"]) for r in raw) == \
        Counter(frame for _, _, _, frame in records)
    assert info.metadata == ("clock", "ground")
    # Unix times, as `mcap info` and Foxglove read them: the run's date, not 1970.
    with open(mcap, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    first_ns, last_ns = summary.statistics.message_start_time, summary.statistics.message_end_time
    assert start_s - 0.1 <= first_ns / 1e9 <= last_ns / 1e9 <= end_s + 0.1
    assert abs(first_ns / 1e9 - time.time()) < 60
    # The station's clock comes back by subtracting the recorded offset.
    offset = int(read_metadata(mcap)["clock"]["unix_offset_ns"])
    assert offset == int(read_metadata(mcap)["ground"]["unix_offset_ns"])
    monotonic_ns = time.monotonic_ns()  # the station's clock (WallClock)
    assert all(m.clock_ns == m.log_time_ns - offset and 0 < monotonic_ns - m.clock_ns < 60 * S
               for m in read_messages(mcap, [topics.MAVLINK_RAW]))


def test_without_log_writes_nothing(vehicle: UdpVehicle, tmp_path: Path,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    assert run_ground(vehicle, "status") == 0
    assert list(cwd.iterdir()) == []


def test_tlog_record_is_big_endian_microseconds_then_the_packet() -> None:
    assert tlog_record(0x0102030405060708, b"\xfd\x09") == \
        b"\x01\x02\x03\x04\x05\x06\x07\x08\xfd\x09"


def heartbeat_packet() -> tuple[mavlink.MAVLink_message, bytes]:
    msg = mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                            0, 0, mavlink.MAV_STATE_ACTIVE, 3)
    return msg, make_codec(255, 190).pack(msg)


def test_tlog_flushes_once_the_oldest_record_is_a_period_old(tmp_path: Path) -> None:
    _, packet = heartbeat_packet()
    tlog = Tlog(*create_tlog(tmp_path, UNIX_NS), flush_period_ns=S // 2, fsync=False)
    size = len(tlog_record(0, packet))
    tlog.write(UNIX_NS, packet, now_ns=0)
    tlog.write(UNIX_NS + S // 4, packet, now_ns=S // 4)
    assert tlog.path.stat().st_size == 0  # buffered
    tlog.write(UNIX_NS + S // 2, packet, now_ns=S // 2)
    assert tlog.path.stat().st_size == 3 * size and tlog.records == 3
    tlog.write(UNIX_NS + S, packet, now_ns=S)
    assert tlog.path.stat().st_size == 3 * size
    tlog.close()
    tlog.close()
    assert tlog.path.stat().st_size == 4 * size and (tlog.records, tlog.lost) == (4, 0)
    assert [t for t, _, _, _ in read_tlog(tlog.path)] == [1_795_274_557.0, 1_795_274_557.25,
                                                          1_795_274_557.5, 1_795_274_558.0]


def test_summary_names_the_files_and_counts_the_packets(tmp_path: Path) -> None:
    msg, packet = heartbeat_packet()
    ground_log = GroundLog(LogConfig(output_dir=str(tmp_path)), ManualClock(), UNIX_NS)
    for now_ns in (0, S):
        ground_log.record("out", packet, msg, now_ns)
    summary = ground_log.summary_text(ground_log.close())
    assert summary == (f"logged 2 packets to {tmp_path / 'ground-0001.mcap'}, "
                       f"{tmp_path / 'ground-20261121-152237.tlog'}")


def test_tlogs_opened_in_the_same_second_get_their_own_files(tmp_path: Path) -> None:
    paths = []
    for i in range(3):
        path, file = create_tlog(tmp_path / "logs", UNIX_NS + i * S // 10)
        file.close()
        paths.append(path)
    assert [path.name for path in paths] == ["ground-20261121-152237.tlog",
                                            "ground-20261121-152237-2.tlog",
                                            "ground-20261121-152237-3.tlog"]


def test_an_unwritable_folder_is_one_input_error(tmp_path: Path) -> None:
    (tmp_path / "file").write_bytes(b"")
    with pytest.raises(InputError, match=r"file/logs: cannot write the ground log: "):
        GroundLog(LogConfig(output_dir=str(tmp_path / "file" / "logs")), ManualClock(), 0)
    assert list(tmp_path.iterdir()) == [tmp_path / "file"]


def test_a_full_disk_stops_the_tlog_and_counts_the_lost_records(
        caplog: pytest.LogCaptureFixture) -> None:
    _, packet = heartbeat_packet()
    with open("/dev/full", "wb") as full:
        tlog = Tlog(Path("/dev/full"), full, flush_period_ns=S, fsync=False)
        for t_s in range(4):
            tlog.write(UNIX_NS + t_s * S, packet, now_ns=t_s * S)
        tlog.close()
    assert (tlog.records, tlog.lost) == (0, 4)  # two lost by the first flush, then each
    assert "/dev/full: tlog stopped, 2 records lost" in caplog.text


def test_sigterm_finishes_the_logs_of_a_running_command(vehicle: UdpVehicle,
                                                         tmp_path: Path) -> None:
    out = tmp_path / "logs"
    watcher = subprocess.Popen(
        [sys.executable, "-m", "tools.cli", "ground", "--connect",
         f"udpout:127.0.0.1:{vehicle.link.local_port}", "--log", str(out), "watch",
         "--duration", "60"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert watcher.stdout is not None
        watcher.stdout.readline()  # watching now
        time.sleep(1.0)
        watcher.send_signal(signal.SIGTERM)
        assert watcher.wait(timeout=10.0) == 128 + signal.SIGTERM
    finally:
        watcher.kill()
    info = log_info(out / "ground-0001.mcap")
    assert info.complete  # summary and index written: the finally blocks ran
    assert read_tlog(next(out.glob("ground-*.tlog")))
