"""log_series (shared/logs/series.py): a rotated log's files in order; overlaps and gaps."""

from __future__ import annotations

from pathlib import Path

import pytest

from shared.config import LogConfig
from shared.errors import InputError
from shared.logs import topics
from shared.logs.series import log_series, series_name
from shared.logs.writer import LogWriter

S = 1_000_000_000


def write(folder: Path, name: str, times_s: list[float], series: str | None = None,
          rotate_s: float = 600.0) -> tuple[Path, ...]:
    """A log of one command per time, rotated every ``rotate_s`` of log time."""
    config = LogConfig(output_dir=str(folder), rotate_period_ns=round(rotate_s * S))
    with LogWriter(config, name) as writer:
        if series is not None:
            writer.add_metadata("run", {"series": series, "route": "loop"})
        for t_s in times_s:
            writer.log_json(round(t_s * S), topics.CMD_VEL, "vmnav.Command", {"stamp_ns": 0})
    return writer.close().files


@pytest.fixture
def two_runs(tmp_path: Path) -> tuple[tuple[Path, ...], tuple[Path, ...]]:
    """Two runs into one folder, rotated every 1 s: robot-0001..0003, then 0004..0005."""
    first = write(tmp_path, "robot", [0.0, 0.5, 1.0, 1.5, 2.0, 2.5], "a", rotate_s=1.0)
    second = write(tmp_path, "robot", [0.0, 0.5, 1.0, 1.5], "b", rotate_s=1.0)
    assert [f.name for f in first + second] == [f"robot-000{i}.mcap" for i in range(1, 6)]
    return first, second


class TestSeries:
    def test_the_first_file_stands_for_its_run(self, two_runs) -> None:
        first, second = two_runs
        assert log_series([first[0]]) == first
        assert log_series([first[1]]) == first[1:]
        assert log_series([second[0]]) == second

    def test_files_given_in_any_order_come_in_order(self, two_runs) -> None:
        first, _ = two_runs
        assert log_series([first[2], first[0], first[1]]) == first

    def test_a_file_without_a_series_is_itself(self, tmp_path: Path) -> None:
        files = write(tmp_path, "drive", [0.0, 1.0, 2.0], rotate_s=1.0)
        assert len(files) == 3 and log_series([files[0]]) == files[:1]
        assert log_series(files) == files

    def test_a_slightly_older_message_after_a_rotation_is_no_overlap(self,
                                                                      tmp_path: Path) -> None:
        # After the rotation at 2.1 s, another thread's message 0.4 s older than the last
        # of the file before.
        files = write(tmp_path, "robot", [0.0, 1.9, 2.1, 1.5], rotate_s=2.0)
        assert len(files) == 2 and log_series(files) == files
        other = write(tmp_path / "other", "robot", [1.5, 3.0])
        with pytest.raises(InputError, match="overlaps"):  # not the next file of the rotation
            log_series([files[0], other[0]])

    def test_name(self, two_runs) -> None:
        first, _ = two_runs
        assert series_name(first[:1]) == str(first[0])
        assert series_name(first) == f"{first[0]} (+2 files)"


class TestBadInput:
    def test_files_of_two_runs(self, two_runs) -> None:
        first, second = two_runs
        with pytest.raises(InputError, match=f"{second[0]}: is not of the same run as "
                                             f"{first[2]} \\(series b and a\\)"):
            log_series([first[2], second[0]])

    def test_a_gap(self, two_runs) -> None:
        first, _ = two_runs
        with pytest.raises(InputError, match=f"{first[1]}: missing from the series: a gap "
                                             f"between robot-0001.mcap and robot-0003.mcap"):
            log_series([first[0], first[2]])

    def test_an_overlap(self, tmp_path: Path) -> None:
        a = write(tmp_path, "a", [0.0, 5.0])
        b = write(tmp_path, "b", [2.0, 7.0])
        with pytest.raises(InputError, match=f"{b[0]}: overlaps {a[0]}: it starts at 2.000 s, "
                                             f"before a-0001.mcap ends at 5.000 s"):
            log_series([a[0], b[0]])

    def test_a_file_given_twice(self, two_runs) -> None:
        first, _ = two_runs
        with pytest.raises(InputError, match="is given twice"):
            log_series([first[0], first[0]])

    def test_an_unfinished_file(self, tmp_path: Path) -> None:
        (file,) = write(tmp_path, "robot", [0.0, 1.0])
        data = file.read_bytes()
        file.write_bytes(data[: len(data) - 40])
        with pytest.raises(InputError, match=f"`vmnav log recover {file}`"):
            log_series([file])

    def test_no_file(self) -> None:
        with pytest.raises(InputError, match="no file given"):
            log_series([])
