"""Hostile MCAP logs (issue 15): one-line errors or skipped chunks, nothing inflated first.

The files are crafted by :mod:`tools.bench.hostile_files`. Before the fix a chunk
declaring 2^63 bytes gave OverflowError (read, recover), a zstd or lz4 bomb was inflated
whole (MemoryError, or hundreds of MB), and a damaged summary gave KeyError (read).
"""

from __future__ import annotations

import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from shared.config import LogConfig
from shared.errors import InputError
from shared.logs import _chunks, topics
from shared.logs.reader import RecoverReport, log_info, read_messages, read_metadata, recover
from shared.logs.writer import LogWriter
from tools.bench import hostile_files

MIB = 2**20
MAX_TRACED_BYTES = 16 * MIB
"""What reading any of them may allocate (see :func:`traced_limit`)."""


CASES: dict[str, tuple[Callable[[Path], None], str]] = {
    "zstd chunk declaring 2^63 bytes": (
        hostile_files.zstd_log_declaring_2_63,
        "a chunk declares 9223372036854775808 bytes uncompressed, more than the 67108864 allowed"),
    "zstd bomb": (lambda p: hostile_files.bomb_log(p, "zstd", 96 * MIB, 96 * MIB),
                  "a chunk declares 100663296 bytes uncompressed, more than the 67108864"),
    "zstd bomb declaring 1 MiB": (lambda p: hostile_files.bomb_log(p, "zstd", 96 * MIB, MIB),
                                  "a chunk declares 1048576 bytes uncompressed but holds more"),
    "lz4 bomb declaring 1 MiB": (lambda p: hostile_files.bomb_log(p, "lz4", 96 * MIB, MIB),
                                 "a chunk declares 1048576 bytes uncompressed but holds more"),
    "chunks inflating to 100 times the file": (
        lambda p: hostile_files.bomb_log(p, "zstd", 40 * MIB, 40 * MIB, chunks=2),
        "its chunks inflate to more than 100 times the file's size"),
    "corrupt summary opcode": (hostile_files.log_with_corrupt_summary,
                               "damaged summary: the summary's chunk at byte"),
}


def traced(action: Callable[[], object]) -> tuple[int, InputError | None]:
    """The most ``action`` had allocated at once, bytes (tracemalloc), and the input
    error it raised (None if it returned)."""
    tracemalloc.start()
    try:
        try:
            action()
        except InputError as e:
            return tracemalloc.get_traced_memory()[1], e
        return tracemalloc.get_traced_memory()[1], None
    finally:
        tracemalloc.stop()


def traced_limit(case: str) -> int:
    """The first 40 MiB chunk of the file inflating to 100 times its size is legitimate."""
    return MAX_TRACED_BYTES + (3 * 40 * MIB if case.startswith("chunks") else 0)


@pytest.mark.parametrize("case", CASES)
def test_read_refuses_in_one_line_without_inflating(tmp_path: Path, case: str) -> None:
    write, fragment = CASES[case]
    path = tmp_path / "hostile.mcap"
    write(path)
    before = path.read_bytes()
    peak_bytes, error = traced(lambda: list(read_messages(path)))
    assert error is not None and peak_bytes < traced_limit(case)
    message = str(error)
    assert "\n" not in message and message.startswith(f"{path}: ") and fragment in message
    assert f"vmnav log recover {path}" in message
    assert path.read_bytes() == before


@pytest.mark.parametrize("case", [c for c in CASES if c != "corrupt summary opcode"])
def test_recover_skips_the_hostile_chunk(tmp_path: Path, case: str) -> None:
    path = tmp_path / "hostile.mcap"
    CASES[case][0](path)
    reports: list[RecoverReport] = []
    peak_bytes, error = traced(lambda: reports.append(recover(path, tmp_path / "out.mcap")))
    assert error is None and peak_bytes < traced_limit(case)
    report = reports[0]
    assert report.skipped_chunks == 1
    assert log_info(report.dst).complete


def test_chunks_overlapping_in_time_may_queue_a_limited_size(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Chunks that all start at 0 ns but hold messages at 1 ns must all be read before
    the first message can be yielded: the queue stops them (limit scaled down 16 times)."""
    monkeypatch.setattr(_chunks, "MAX_QUEUED_BYTES", 8 * MIB)
    path = tmp_path / "overlap.mcap"
    hostile_files.bomb_log(path, "zstd", 3 * MIB, 3 * MIB, chunks=4)
    with pytest.raises(InputError, match="chunks overlapping in log time up to the one at byte "
                       r"\d+ hold 9437122 bytes at once, more than the 8388608 allowed"):
        list(read_messages(path))
    assert recover(path, tmp_path / "out.mcap").messages == 4  # one chunk at a time


def test_info_and_recover_of_a_damaged_summary_use_the_data_section(tmp_path: Path) -> None:
    path = tmp_path / "hostile.mcap"
    hostile_files.log_with_corrupt_summary(path)
    info = log_info(path)
    assert not info.complete and info.message_count == 200
    assert info.problem is not None and info.problem.startswith("damaged summary: ")
    report = recover(path, tmp_path / "out.mcap")
    assert report.messages == 200 and len(list(read_messages(report.dst))) == 200


def test_messages_come_in_log_time_order_as_mcap_reads_them(tmp_path: Path) -> None:
    """Log times out of order across overlapping chunks, ties included: the checked
    reader yields mcap's SeekingReader order."""
    rng = np.random.default_rng(3)
    config = LogConfig(output_dir=str(tmp_path), chunk_size_bytes=1024, queue_messages=401)
    with LogWriter(config, "robot") as writer:
        for t in rng.integers(0, 50, size=400) * 10**6:
            writer.log_json(int(t), topics.CMD_VEL if t % 3 else topics.SERVO_STATE,
                            "vmnav.Command", {"stamp_ns": int(t)})
    (path,) = writer.stats().files
    with open(path, "rb") as f:
        expected = [(c.topic, m.log_time, m.sequence)
                    for _, c, m in make_reader(f).iter_messages(topics=[topics.SERVO_STATE])]
    got = [(m.topic, m.log_time_ns, m.sequence)
           for m in read_messages(path, [topics.SERVO_STATE])]
    assert got == expected and len(got) > 50


def test_a_message_nested_too_deep_names_its_topic(tmp_path: Path) -> None:
    config = LogConfig(output_dir=str(tmp_path))
    deep: dict[str, object] = {}
    for _ in range(40):
        deep = {"a": deep}
    with LogWriter(config, "robot") as writer:
        writer.log_json(0, topics.SERVO_STATE, "vmnav.ServoState", {"stamp_ns": 0})
        writer.log_json(1, topics.SERVO_STATE, "vmnav.ServoState", deep)
    (path,) = writer.stats().files
    with pytest.raises(InputError) as error:
        list(read_messages(path))
    assert str(error.value) == (f"{path}: /servo/state message 2: not valid JSON: arrays and "
                                "objects nest more than 32 deep")


# -- fuzz: mutated logs give results or InputError, never anything else --------------------


@pytest.fixture(scope="module")
def valid_logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    return {compression: hostile_files.write_valid_log(
        tmp_path_factory.mktemp(compression), compression, count=60).read_bytes()
        for compression in ("zstd", "lz4", "none")}


@settings(derandomize=True, max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(compression=st.sampled_from(["zstd", "lz4", "none"]),
       edits=st.lists(st.tuples(st.floats(0.0, 1.0), st.binary(min_size=1, max_size=9)),
                      min_size=1, max_size=4),
       cut=st.floats(0.5, 1.0))
def test_fuzz_mutated_logs_give_results_or_input_errors(
    valid_logs: dict[str, bytes], tmp_path: Path, compression: str,
    edits: list[tuple[float, bytes]], cut: float
) -> None:
    data = bytearray(valid_logs[compression])
    for where, payload in edits:  # overwrite: lengths, opcodes, sizes, CRCs, data alike
        at = int(where * (len(data) - len(payload)))
        data[at:at + len(payload)] = payload
    path = tmp_path / "fuzzed.mcap"
    path.write_bytes(bytes(data[:max(8, int(cut * len(data)))]))
    for action in (log_info, lambda p: list(read_messages(p)), read_metadata,
                   lambda p: recover(p, tmp_path / "out.mcap")):
        try:
            action(path)
        except InputError as e:
            assert "\n" not in str(e)
