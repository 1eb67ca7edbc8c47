"""``vmnav log info`` / ``vmnav log recover`` (and ``vmnav bench log``) through the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from shared.config import LogConfig
from shared.logs import topics
from shared.logs.writer import LogWriter
from tools.cli import main

MS = 1_000_000
#: Unix time at the writer clock's zero (2025-11-14 16:00:00 UTC), ns.
EPOCH_NS = 1_763_136_000_000_000_000


@pytest.fixture
def log_file(tmp_path: Path) -> Path:
    """A finished log: 2 s of 50 Hz servo state and 15 frames/s of 40x60 images."""
    config = LogConfig(output_dir=str(tmp_path / "logs"), chunk_size_bytes=4096,
                       queue_messages=1000)
    image = np.random.default_rng(0).integers(0, 255, (40, 60), dtype=np.uint8)
    with LogWriter(config, "robot", unix_offset_ns=EPOCH_NS) as writer:
        writer.add_metadata("run", {"route": "corridor"})
        for i in range(101):
            t_ns = 1500 * MS + i * 20 * MS
            writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState", {"stamp_ns": t_ns})
            writer.log_image(t_ns, topics.CAMERA_IMAGE, image)
    (path,) = writer.stats().files
    return path


def test_info_prints_a_table(log_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "info", str(log_file)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"file      {log_file} (")
    assert lines[1] == "status    complete (summary and index)"
    assert lines[2].startswith("duration  2.00 s, ") and "metadata: clock, run" in lines[2]
    assert lines[3] == "started   2025-11-14 16:00:01.500 UTC (the writer's clock: 1.500 s)"
    assert lines[4].split() == ["topic", "schema", "messages", "rate", "Hz"]
    rows = {line.split()[0]: line.split()[1:] for line in lines[5:]}
    assert rows[topics.SERVO_STATE] == ["vmnav.ServoState", "101", "50.50"]
    assert rows[topics.CAMERA_IMAGE][0] == "foxglove.CompressedImage"
    assert 30 <= int(rows[topics.CAMERA_IMAGE][1]) <= 31  # 15 frames/s of the 50 Hz stream


def test_info_json(log_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["log", "info", str(log_file), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert (info["complete"], info["duration_s"], info["metadata"]) == (True, 2.0,
                                                                         ["clock", "run"])
    assert (info["start_ns"], info["unix_offset_ns"]) == (EPOCH_NS + 1500 * MS, EPOCH_NS)
    assert {t["topic"]: t["schema_name"] for t in info["topics"]} == {
        topics.CAMERA_IMAGE: "foxglove.CompressedImage", topics.SERVO_STATE: "vmnav.ServoState"}


def test_info_and_recover_of_a_truncated_log(log_file: Path, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log_file.read_bytes()[: log_file.stat().st_size * 2 // 3])
    assert main(["log", "info", str(cut)]) == 0
    status = capsys.readouterr().out.splitlines()[1]
    assert status.startswith("status    truncated: the record at byte ")
    assert status.endswith(f"`vmnav log recover {cut}` rewrites it into a valid file")
    assert main(["log", "recover", str(cut)]) == 0
    out = capsys.readouterr().out.splitlines()
    recovered = tmp_path / "cut.recovered.mcap"
    assert out[0].startswith(f"wrote {recovered}: ") and " messages on 2 topics, " in out[0]
    assert out[1].startswith(f"{cut}: truncated: ")
    assert main(["log", "info", str(recovered)]) == 0
    assert capsys.readouterr().out.splitlines()[1] == "status    complete (summary and index)"


def test_recover_to_a_chosen_file(log_file: Path, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "copy.mcap"
    assert main(["log", "recover", str(log_file), "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [f"wrote {out}: 132 messages on 2 topics, 2.00 s",
                     f"{log_file} was already complete; the copy holds the same messages"]


@pytest.mark.parametrize("command", ["info", "recover"])
def test_bad_files_give_one_line_errors(tmp_path: Path, command: str,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(np.random.default_rng(1).bytes(3000))
    assert main(["log", command, str(junk)]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"vmnav log: error: {junk}: not an MCAP file (3000 bytes; ")
    assert captured.err.count("\n") == 1
    assert main(["log", command, str(tmp_path / "missing.mcap")]) == 1
    assert capsys.readouterr().err == (f"vmnav log: error: {tmp_path / 'missing.mcap'}: "
                                       "cannot read: No such file or directory\n")


def test_bench_log_prints_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "log", "--seconds", "0.8"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["benchmark"] == "log"
    assert result["messages_written"] > 0 and result["dropped"] == result["lost"] == 0
    assert isinstance(result["log_overhead_core_fraction"], float)
    assert result["jpeg_kb_mean"] > 50
