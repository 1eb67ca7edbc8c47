"""Retention of the log folder (shared/logs/retention.py): size and age limits over vmnav's
own log files only, never the file being written, and the limits' config checks."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest
from mcap.writer import Writer

from robot.config import load_config
from shared.config import LogConfig, load_log_config
from shared.errors import ConfigError
from shared.logs import topics
from shared.logs._mcap_files import LIBRARY
from shared.logs.retention import ACTIVE_S, SECONDS_PER_DAY, is_vmnav_log, prune_logs
from shared.logs.writer import LogWriter
from tools.cli import main

MB = 1_000_000
NOW_S = 1_763_136_000.0  # 2025-11-14 16:00:00 UTC


def mcap_file(path: Path, size: int, age_s: float, library: str = LIBRARY,
              now_s: float = NOW_S) -> Path:
    """An MCAP file of about ``size`` bytes whose header names ``library``, last modified
    ``age_s`` before ``now_s``."""
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="", library=library)
        writer.add_attachment(0, 0, "padding", "application/octet-stream", bytes(size))
        writer.finish()
    os.utime(path, (now_s - age_s, now_s - age_s))
    return path


def other_file(path: Path, size: int, age_s: float, now_s: float = NOW_S) -> Path:
    path.write_bytes(bytes(size))
    os.utime(path, (now_s - age_s, now_s - age_s))
    return path


def config(**limits: float) -> LogConfig:
    return LogConfig(**{"retain_max_bytes": 0, "retain_max_age_days": 0, **limits})


def names(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir()}


class TestSizeLimit:
    def test_the_oldest_go_until_the_rest_fit(self, tmp_path: Path) -> None:
        for n, age_h in enumerate((5, 4, 3, 2, 1), start=1):
            mcap_file(tmp_path / f"robot-{n:04d}.mcap", MB, age_h * 3600)
        pruned = prune_logs(tmp_path, config(retain_max_bytes=3 * MB + 5000), LIBRARY, NOW_S)
        assert [p.name for p in pruned.removed] == ["robot-0001.mcap", "robot-0002.mcap"]
        assert pruned.freed_bytes > 2 * MB and pruned.errors == 0
        assert names(tmp_path) == {"robot-0003.mcap", "robot-0004.mcap", "robot-0005.mcap"}

    def test_tlogs_count_and_go_too(self, tmp_path: Path) -> None:
        other_file(tmp_path / "ground-20251101-120000.tlog", 2 * MB, 10 * 3600)
        other_file(tmp_path / "ground-20251101-120000-2.tlog", 2 * MB, 9 * 3600)
        mcap_file(tmp_path / "ground-0001.mcap", MB, 3600)
        prune_logs(tmp_path, config(retain_max_bytes=3 * MB + 5000), LIBRARY, NOW_S)
        assert names(tmp_path) == {"ground-20251101-120000-2.tlog", "ground-0001.mcap"}

    def test_the_file_being_written_and_recent_files_stay_over_the_limit(
            self, tmp_path: Path) -> None:
        old = mcap_file(tmp_path / "robot-0001.mcap", MB, 3600)
        active = mcap_file(tmp_path / "robot-0002.mcap", MB, ACTIVE_S - 1)
        current = mcap_file(tmp_path / "robot-0003.mcap", MB, 2 * 3600)  # older, but kept
        pruned = prune_logs(tmp_path, config(retain_max_bytes=MB), LIBRARY, NOW_S,
                            keep=[current])
        assert pruned.removed == (old,)
        assert active.exists() and current.exists()


class TestAgeLimit:
    def test_files_older_than_the_limit_go(self, tmp_path: Path) -> None:
        mcap_file(tmp_path / "teach-corridor-0001.mcap", 1000, 31 * SECONDS_PER_DAY)
        other_file(tmp_path / "ground-20251001-080000.tlog", 1000, 40 * SECONDS_PER_DAY)
        mcap_file(tmp_path / "robot-0007.mcap", 1000, 29 * SECONDS_PER_DAY)
        pruned = prune_logs(tmp_path, config(retain_max_age_days=30), LIBRARY, NOW_S)
        assert {p.name for p in pruned.removed} == {"teach-corridor-0001.mcap",
                                                    "ground-20251001-080000.tlog"}
        assert names(tmp_path) == {"robot-0007.mcap"}

    def test_no_limits_remove_nothing(self, tmp_path: Path) -> None:
        mcap_file(tmp_path / "robot-0001.mcap", MB, 3000 * SECONDS_PER_DAY)
        assert prune_logs(tmp_path, config(), LIBRARY, NOW_S).removed == ()


def test_foreign_files_are_left_alone(tmp_path: Path) -> None:
    old = 400 * SECONDS_PER_DAY
    foreign = [
        other_file(tmp_path / "notes.txt", MB, old),
        other_file(tmp_path / "robot-0001.mcap.bak", MB, old),
        mcap_file(tmp_path / "flight-0001.mcap", MB, old, library="foxglove-sdk"),
        other_file(tmp_path / "robot-0002.mcap", MB, old),  # our name, not an MCAP file
        mcap_file(tmp_path / "robot-0003.recovered.mcap", MB, old),  # a user's copy
        other_file(tmp_path / "flight.tlog", MB, old),
        other_file(tmp_path / "ground-latest.tlog", MB, old),
    ]
    (tmp_path / "old").mkdir()
    below = mcap_file(tmp_path / "old" / "robot-0001.mcap", MB, old)
    (tmp_path / "robot-0009.mcap").symlink_to(below)
    ours = mcap_file(tmp_path / "robot-0004.mcap", MB, old)
    pruned = prune_logs(tmp_path, config(retain_max_bytes=MB, retain_max_age_days=1), LIBRARY,
                        NOW_S)
    assert pruned.removed == (ours,)
    assert all(p.exists() for p in (*foreign, below))
    assert (tmp_path / "robot-0009.mcap").is_symlink()


def test_is_vmnav_log_reads_the_header(tmp_path: Path) -> None:
    assert is_vmnav_log(mcap_file(tmp_path / "a-0001.mcap", 10, 0), LIBRARY)
    assert not is_vmnav_log(mcap_file(tmp_path / "b-0001.mcap", 10, 0, library="x"), LIBRARY)
    assert not is_vmnav_log(other_file(tmp_path / "c-0001.mcap", 3, 0), LIBRARY)
    assert not is_vmnav_log(other_file(tmp_path / "d-0001.mcap", 0, 0), LIBRARY)


def test_the_writer_prunes_when_it_opens_a_file(tmp_path: Path) -> None:
    now_s = time.time()
    for n in range(1, 4):
        mcap_file(tmp_path / f"robot-{n:04d}.mcap", MB, (10 - n) * 3600, now_s=now_s)
    keep = other_file(tmp_path / "README.txt", 5 * MB, 500 * SECONDS_PER_DAY, now_s=now_s)
    limits = LogConfig(output_dir=str(tmp_path), retain_max_bytes=2 * MB + 10_000,
                       retain_max_age_days=30)
    with LogWriter(limits, "robot") as writer:
        writer.log_json(0, topics.CMD_VEL, "vmnav.Command", {"stamp_ns": 0})
    (new,) = writer.stats().files
    assert new.name == "robot-0004.mcap"  # numbering goes on after the deleted files
    assert names(tmp_path) == {"robot-0002.mcap", "robot-0003.mcap", "robot-0004.mcap",
                               "README.txt"}
    assert keep.exists()


BAD_VALUES = [
    ("retain_max_bytes = -1", "retain_max_bytes must be 0 (no limit) or at least 1000000 "
                              "(1 MB), got -1"),
    ("retain_max_bytes = 500", "retain_max_bytes must be 0 (no limit) or at least 1000000 "
                               "(1 MB), got 500"),
    ("retain_max_bytes = 1.5e9", "retain_max_bytes"),
    ("retain_max_bytes = \"50 GB\"", "retain_max_bytes"),
    ("retain_max_age_days = -3", "retain_max_age_days must be 0 (no limit) or in (0, 36500] "
                                 "days, got -3"),
    ("retain_max_age_days = 40000", "retain_max_age_days must be 0 (no limit) or in "
                                    "(0, 36500] days, got 40000"),
    ("retain_max_age_days = nan", "retain_max_age_days"),
    ("retain_max_age_days = inf", "retain_max_age_days"),
    ("retain_max_age_days = true", "retain_max_age_days"),
]


@pytest.mark.parametrize(("line", "message"), BAD_VALUES)
def test_bad_limits_are_one_line_config_errors(tmp_path: Path, line: str, message: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "vmnav.toml"
    path.write_text(f"[log]\n{line}\n")
    for load in (load_config, load_log_config):  # the robot's config, the ground station's
        with pytest.raises(ConfigError) as error:
            load(path)
        text = str(error.value)
        assert "\n" not in text and text.startswith(str(path)) and message in text, text
    # The ground station refuses it before it connects to anything.
    assert main(["ground", "--config", str(path), "--log", str(tmp_path / "logs"),
                 "status"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and str(path) in err
    assert not (tmp_path / "logs").exists()
