"""tools/bench/hostile_files.py: its crafted files are what they claim, and the real
commands refuse them in a fresh process within the memory target."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from tools.bench import hostile_files
from tools.bench.hostile_files import (
    MAX_RSS_MB,
    deflated_zeros_npy,
    run_command,
    stored_npy,
    zip_archive,
)


def test_crafted_archives_are_valid_npz_files_numpy_reads() -> None:
    """The bombs are real: numpy inflates the deflated one to its declared zeros (CRC
    included), so refusing them is the readers' doing, not a broken archive's."""
    pixels = np.arange(24.0).reshape(12, 2)
    data = zip_archive([stored_npy("pixels_xy", pixels),
                        deflated_zeros_npy("patches", "<f4", (2**10, 512))])
    with np.load(io.BytesIO(data)) as archive:
        assert np.array_equal(archive["pixels_xy"], pixels)
        patches = archive["patches"]
        assert patches.shape == (1024, 512) and not patches.any()
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        assert archive.testzip() is None
        assert archive.getinfo("patches.npy").compress_size < 4096


def test_crafted_bomb_log_is_a_finished_mcap_file(tmp_path: Path) -> None:
    path = tmp_path / "bomb.mcap"
    hostile_files.bomb_log(path, "lz4", 4 * 2**20, 4 * 2**20)
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.chunk_indexes[0].uncompressed_size == 4 * 2**20
    assert [c.topic for c in summary.channels.values()] == ["/servo/state"]


def test_memory_info_refuses_the_npz_bomb_in_one_line(tmp_path: Path) -> None:
    memory = tmp_path / "memory"
    hostile_files.write_valid_memory(memory, seed=0)
    hostile_files.npz_bomb(memory)
    run = run_command(["memory", "info", "--memory", str(memory)], tmp_path)
    assert run.refused_one_line, run.stderr
    assert "features/0.npz: its arrays declare 671089088 bytes uncompressed" in run.stderr
    assert 0 < run.peak_rss_mb < MAX_RSS_MB


@pytest.mark.slow
def test_measure_meets_its_targets() -> None:
    result = hostile_files.measure()
    assert result["targets_met"], result
    assert len(result["runs"]) == len(hostile_files.MEMORY_CASES) + 3 * len(  # type: ignore[arg-type]
        hostile_files.LOG_CASES)
