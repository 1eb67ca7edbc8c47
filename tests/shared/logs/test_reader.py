"""log_info, read_messages and recover on finished, killed, truncated, damaged and foreign files."""

from __future__ import annotations

import hashlib
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from shared.config import LogConfig
from shared.errors import InputError
from shared.logs import topics
from shared.logs.reader import log_info, read_messages, recover
from shared.logs.writer import LogWriter

ROOT = Path(__file__).resolve().parents[3]
MS = 1_000_000


def write_log(folder: Path, count: int = 300) -> Path:
    """A finished log of ``count`` commands 10 ms apart in chunks of about 2 kB."""
    config = LogConfig(output_dir=str(folder), chunk_size_bytes=2048, queue_messages=count + 1)
    with LogWriter(config, "robot") as writer:
        for i in range(count):
            writer.log_json(i * 10 * MS, topics.CMD_VEL, "vmnav.Command",
                            {"stamp_ns": i * 10 * MS, "linear_x_m_s": 0.3,
                             "angular_z_rad_s": 0.01 * i, "source": "servo"})
        writer.log_text(count * 10 * MS, "INFO", "done", "robot")
    (path,) = writer.stats().files
    return path


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def one_line(error: pytest.ExceptionInfo[InputError], path: Path) -> str:
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{path}: ")
    return message


def test_info_of_a_finished_log(tmp_path: Path) -> None:
    info = log_info(write_log(tmp_path))
    assert info.complete and info.problem is None
    assert info.message_count == 301
    assert (info.start_ns, info.end_ns, info.duration_s) == (0, 3000 * MS, 3.0)
    assert [(t.topic, t.schema_name, t.message_count) for t in info.topics] == [
        ("/cmd_vel", "vmnav.Command", 300), ("/log", "foxglove.Log", 1)]
    assert info.topics[0].rate_hz == pytest.approx(100.0)


def test_truncated_log_is_scanned_and_refused_by_read_messages(tmp_path: Path) -> None:
    path = write_log(tmp_path)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    info = log_info(cut)
    assert not info.complete and info.problem is not None
    assert info.problem.startswith("truncated: the record at byte")
    assert 0 < info.message_count < 300
    with pytest.raises(InputError) as error:
        list(read_messages(cut))
    assert f"vmnav log recover {cut}" in one_line(error, cut)
    report = recover(cut, tmp_path / "cut.recovered.mcap")
    assert report.messages == info.message_count and not report.source_complete
    assert [m.data["angular_z_rad_s"] for m in read_messages(report.dst)] == pytest.approx(
        [0.01 * i for i in range(report.messages)])


@pytest.mark.parametrize(("content", "fragment"), [
    (bytes(range(256)) * 20, "not an MCAP file (5120 bytes; starts with 00 01 02 03"),
    (b"", "not an MCAP file (0 bytes; is empty"),
])
def test_foreign_files_give_one_line_errors(tmp_path: Path, content: bytes,
                                            fragment: str) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(content)
    for action in (log_info, lambda p: list(read_messages(p)),
                   lambda p: recover(p, tmp_path / "out.mcap")):
        with pytest.raises(InputError) as error:
            action(path)
        assert fragment in one_line(error, path)
    assert not (tmp_path / "out.mcap").exists()


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.mcap"
    with pytest.raises(InputError) as error:
        log_info(path)
    assert one_line(error, path).endswith("cannot read: No such file or directory")


def test_recover_skips_a_damaged_chunk_and_keeps_the_rest(tmp_path: Path) -> None:
    path = write_log(tmp_path)
    with open(path, "rb") as f:
        chunk = make_reader(f).get_summary().chunk_indexes[1]
    in_chunk = [m for m in read_messages(path)
                if chunk.message_start_time <= m.log_time_ns <= chunk.message_end_time]
    data = bytearray(path.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length // 2] ^= 0xFF
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    with pytest.raises(InputError) as error:
        list(read_messages(damaged))
    assert "damaged" in one_line(error, damaged)
    before = digest(damaged)
    report = recover(damaged, tmp_path / "fixed.mcap")
    assert digest(damaged) == before  # the source is only read
    assert report.skipped_chunks == 1
    assert report.messages == 301 - len(in_chunk) > 250
    assert log_info(report.dst).complete


def test_recover_of_a_finished_log_copies_everything(tmp_path: Path) -> None:
    path = write_log(tmp_path)
    report = recover(path, tmp_path / "copy.mcap")
    assert report.source_complete and report.problem is None
    assert (report.messages, report.topics, report.skipped_chunks) == (301, 2, 0)
    assert list(read_messages(report.dst)) == list(read_messages(path))
    with pytest.raises(InputError, match="the output must be another file"):
        recover(path, path)


def test_kill_9_loses_at_most_the_last_second(tmp_path: Path) -> None:
    """A writer logs a counter at 100 Hz (plus frames) and is SIGKILLed after about 2 s:
    the recovered counters run from 0 without a gap up to one logged less than 1 s
    before the kill, so every message older than 1 s survived."""
    process = subprocess.Popen(
        [sys.executable, "-m", "tests.shared.logs.writer_process", "counter", str(tmp_path)],
        cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None and process.stdout.readline() == "started\n"
        time.sleep(2.0)
        kill_ns = time.monotonic_ns()  # CLOCK_MONOTONIC, the writer's clock too
    finally:
        process.kill()
        process.wait()
        process.stdout.close()
    (path,) = tmp_path.glob("killed-*.mcap")
    info = log_info(path)
    assert not info.complete and info.problem is not None
    report = recover(path, tmp_path / "recovered.mcap")
    counters = list(read_messages(report.dst, ["/counter"]))
    assert [int(m.data["message"]) for m in counters] == list(range(len(counters)))
    assert counters[-1].log_time_ns >= kill_ns - 1_000_000_000
    assert len(counters) >= 100  # the run was longer than a second
    assert log_info(report.dst).complete


@pytest.mark.parametrize("value", ["-5", "12.5", "1e9", " 7", "99999999999999999999", ""])
def test_a_malformed_clock_offset_is_refused_in_one_line(tmp_path: Path, value: str) -> None:
    from mcap.writer import Writer

    path = tmp_path / "bad-clock.mcap"
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="", library="test")
        writer.add_metadata(topics.CLOCK_METADATA, {topics.UNIX_OFFSET_KEY: value})
        writer.finish()
    for action in (log_info, lambda p: list(read_messages(p))):
        with pytest.raises(InputError, match="expected an integer number of ns >= 0") as error:
            action(path)
        one_line(error, path)
