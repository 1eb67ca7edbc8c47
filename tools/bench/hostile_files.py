"""Hostile files: crafted memory folders and MCAP logs, each opened by the real command in
a fresh process; peak RSS, time and how each was refused.

Issue 15 found tracebacks (RecursionError, OverflowError, MemoryError, TypeError,
NotImplementedError, KeyError) and decompression bombs that allocate gigabytes before
any check. The builders here craft each of those files; the tests of the readers use
them too (``tests/shared/memory/test_hostile_memory.py``, ``tests/shared/logs/
test_hostile_logs.py``). :func:`measure` builds a valid memory and a valid log with
vmnav's own writers, damages copies of them, and runs ``vmnav memory info`` on each
memory and ``vmnav log info``, ``vmnav log plot`` (which reads the messages) and
``vmnav log recover`` on each log, one child process per run.

Targets: every run ends without a traceback within the time limit, at a peak RSS below
400 MB; a command that cannot use the file refuses it with one line on stderr (exit 1),
``log info`` and ``log recover`` report what is damaged and skip it (exit 0).
"""

from __future__ import annotations

import io
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import lz4.frame
import numpy as np
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.reader import make_reader
from mcap.records import (
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Schema,
    Statistics,
)

from shared.camera_model import CameraModel
from shared.config import LogConfig
from shared.logs import topics
from shared.logs.writer import LogWriter
from shared.memory import KeyframeRecord, add_path_to_disk
from shared.memory.store import MANIFEST_NAME, features_path
from shared.pose import Pose2

ROOT = Path(__file__).resolve().parents[2]
MAX_RSS_MB = 400.0
"""Target: the peak resident memory of every run, MB."""
RUN_TIMEOUT_S = 120.0
"""A run still going after this long counts as a hang."""
MB = 1e6
MIB = 2**20
_MCAP_MAGIC = b"\x89MCAP0\r\n"

# -- zip and .npy crafting ----------------------------------------------------------------


@dataclass(frozen=True)
class ZipEntry:
    """One member of a hand-made zip archive, fields as the zip format declares them.

    Attributes:
        name: e.g. ``patches.npy``.
        raw: the bytes stored (compressed with ``method``).
        crc: CRC-32 of the uncompressed bytes.
        size: the declared uncompressed size, bytes (< 4 GiB: no zip64).
        method: 0 stored, 8 deflated, anything else for hostile files.
        version: the "version needed to extract" (20 = 2.0; above 63 is not supported).
    """

    name: str
    raw: bytes
    crc: int
    size: int
    method: int = 0
    version: int = 20


def zip_archive(entries: Sequence[ZipEntry]) -> bytes:
    """A zip archive (local headers, central directory, end record) of ``entries``."""
    out = bytearray()
    central = bytearray()
    for e in entries:
        name = e.name.encode()
        offset = len(out)
        out += struct.pack("<4s5H3L2H", b"PK\x03\x04", e.version, 0, e.method, 0, 0, e.crc,
                           len(e.raw), e.size, len(name), 0) + name + e.raw
        central += struct.pack("<4s6H3L5H2L", b"PK\x01\x02", 20, e.version, 0, e.method, 0, 0,
                               e.crc, len(e.raw), e.size, len(name), 0, 0, 0, 0, 0,
                               offset) + name
    end = struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, len(entries), len(entries),
                      len(central), len(out), 0)
    return bytes(out + central + end)


def npy_header(dtype: str, shape: tuple[int, ...]) -> bytes:
    """The .npy magic and version 1.0 header declaring ``shape`` of ``dtype`` (e.g. ``<f4``)."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buffer, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buffer.getvalue()


def stored_npy(name: str, array: np.ndarray) -> ZipEntry:
    """``array`` as an uncompressed ``<name>.npy`` member (what ``np.savez`` writes)."""
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, array, allow_pickle=False)
    data = buffer.getvalue()
    return ZipEntry(f"{name}.npy", data, zlib.crc32(data), len(data))


def deflated_zeros_npy(name: str, dtype: str, shape: tuple[int, ...]) -> ZipEntry:
    """A deflated ``<name>.npy`` member of ``shape`` zeros whose size is whole MiB, built
    in milliseconds whatever its size: after a full flush deflate forgets its history, so
    every MiB of zeros compresses to the same bytes (about 1 kB: a 1000:1 bomb)."""
    header = npy_header(dtype, shape)
    n_bytes = int(np.prod(shape)) * np.dtype(dtype).itemsize
    if n_bytes % MIB:
        raise ValueError(f"{shape} {dtype} is not a whole number of MiB")
    deflate = zlib.compressobj(9, zlib.DEFLATED, -15)
    start = deflate.compress(header) + deflate.flush(zlib.Z_FULL_FLUSH)
    block = deflate.compress(bytes(MIB)) + deflate.flush(zlib.Z_FULL_FLUSH)
    raw = start + block * (n_bytes // MIB) + deflate.flush()
    crc = zlib.crc32(header)
    zeros = bytes(MIB)
    for _ in range(n_bytes // MIB):
        crc = zlib.crc32(zeros, crc)
    return ZipEntry(f"{name}.npy", raw, crc, len(header) + n_bytes, method=8)


# -- hostile memory folders: each damages one file of a valid memory ----------------------


def _replace_features(directory: Path, entries: Sequence[ZipEntry]) -> None:
    features_path(directory, 0).write_bytes(zip_archive(entries))


def _valid_pixels() -> ZipEntry:
    return stored_npy("pixels_xy", np.zeros((12, 2)))


def deep_json_manifest(directory: Path) -> None:
    """The manifest's junctions nested 100,000 arrays deep (was: RecursionError)."""
    path = directory / MANIFEST_NAME
    text = path.read_text()
    path.write_text(re.sub(r'"junctions": \[[^\]]*\]',
                           '"junctions": ' + "[" * 100_000 + "]" * 100_000, text))


def huge_int_manifest(directory: Path) -> None:
    """A key image's distance_m is the integer 10^400 (was: OverflowError)."""
    path = directory / MANIFEST_NAME
    path.write_text(re.sub(r'"distance_m": [0-9.e+-]+', '"distance_m": 1' + "0" * 400,
                           path.read_text(), count=1))


def absurd_shape_npz(directory: Path) -> None:
    """pixels_xy's header declares 2^40 x 2 float64 (16 TiB) and holds none (was: MemoryError)."""
    header = npy_header("<f8", (2**40, 2))
    _replace_features(directory, [
        ZipEntry("pixels_xy.npy", header, zlib.crc32(header), len(header)),
        stored_npy("patches", np.zeros((12, 25), np.float32))])


def overflowing_shape_npz(directory: Path) -> None:
    """patches' header declares 2^62 x 2^62 float32, more elements than int64 counts."""
    header = npy_header("<f4", (2**62, 2**62))
    _replace_features(directory, [
        _valid_pixels(),
        ZipEntry("patches.npy", header, zlib.crc32(header), len(header))])


def unparsable_npy_header(directory: Path) -> None:
    """pixels_xy's .npy header is Python text cut short (numpy's reader parses it as Python:
    was tokenize.TokenError)."""
    text = b"{'descr': '<f8', 'fortran_order': False, 'shape': (12, \n"
    header = b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text
    _replace_features(directory, [
        ZipEntry("pixels_xy.npy", header, zlib.crc32(header), len(header)),
        stored_npy("patches", np.zeros((12, 25), np.float32))])


def zip_version_npz(directory: Path) -> None:
    """A member needing zip version 6.4 (was: NotImplementedError)."""
    pixels = _valid_pixels()
    _replace_features(directory, [
        ZipEntry(pixels.name, pixels.raw, pixels.crc, pixels.size, version=64),
        stored_npy("patches", np.zeros((12, 25), np.float32))])


def zip_method_npz(directory: Path) -> None:
    """A member compressed by method 99 (AES, unknown here; was: NotImplementedError)."""
    pixels = _valid_pixels()
    _replace_features(directory, [
        ZipEntry(pixels.name, pixels.raw, pixels.crc, pixels.size, method=99),
        stored_npy("patches", np.zeros((12, 25), np.float32))])


def npz_bomb(directory: Path, mib: int = 640) -> None:
    """patches: 2^18 x ``mib`` float32 zeros, ``mib`` MiB deflated to about ``mib`` kB
    (640 MiB: a 650 kB file); each axis within what a 640x480 camera allows."""
    _replace_features(directory, [
        _valid_pixels(), deflated_zeros_npy("patches", "<f4", (2**18, mib))])


MEMORY_CASES: dict[str, Callable[[Path], None]] = {
    "deep_json_manifest": deep_json_manifest,
    "huge_int_manifest": huge_int_manifest,
    "absurd_shape_npz": absurd_shape_npz,
    "overflowing_shape_npz": overflowing_shape_npz,
    "unparsable_npy_header": unparsable_npy_header,
    "zip_version_npz": zip_version_npz,
    "zip_method_npz": zip_method_npz,
    "npz_bomb": npz_bomb,
}
"""Name -> what it does to a valid memory folder."""


def write_valid_memory(directory: Path, seed: int) -> None:
    """A memory of one path of 3 key images of random grey levels, default camera."""
    rng = np.random.default_rng(seed)
    camera = CameraModel.default()
    records = []
    for i in range(3):
        patches = rng.standard_normal((40, 121)).astype(np.float32)
        records.append(KeyframeRecord(
            t_ns=i * 10**9, odom_pose=Pose2(0.5 * i, 0.0, 0.0), distance_m=0.5 * i,
            image=rng.integers(0, 256, (camera.height, camera.width), dtype=np.uint8),
            pixels_xy=rng.uniform([0, 0], [camera.width - 1, camera.height - 1], (40, 2)),
            patches=patches / np.linalg.norm(patches, axis=1, keepdims=True)))
    add_path_to_disk(directory, camera, "hostile", records)


# -- hostile MCAP logs ------------------------------------------------------------------


def write_valid_log(folder: Path, compression: str = "zstd", count: int = 200) -> Path:
    """A finished robot log of ``count`` servo states, written by vmnav's LogWriter."""
    config = LogConfig(output_dir=str(folder), chunk_size_bytes=2048, compression=compression,
                       queue_messages=count + 1)
    with LogWriter(config, "robot") as writer:
        for i in range(count):
            writer.log_json(i * 10**7, topics.SERVO_STATE, "vmnav.Command",
                            {"stamp_ns": i * 10**7, "linear_x_m_s": 0.3,
                             "angular_z_rad_s": 0.0, "source": "servo"})
    (path,) = writer.stats().files
    return path


def chunk_declaring(path: Path, uncompressed_bytes: int) -> None:
    """The first chunk of the log at ``path`` declares ``uncompressed_bytes`` (e.g. 2^63)."""
    with open(path, "rb") as f:
        offset = make_reader(f).get_summary().chunk_indexes[0].chunk_start_offset
    data = bytearray(path.read_bytes())
    field = offset + 1 + 8 + 16  # opcode, record length, message start and end times
    data[field:field + 8] = struct.pack("<Q", uncompressed_bytes)
    path.write_bytes(bytes(data))


def corrupt_summary_channel(path: Path) -> None:
    """The summary's first Channel record gets an unknown opcode (was: KeyError on read)."""
    data = bytearray(path.read_bytes())
    footer = len(data) - len(_MCAP_MAGIC) - 29  # Footer: opcode, length, 8 + 8 + 4 bytes
    (at,) = struct.unpack_from("<Q", data, footer + 9)  # summary_start
    while data[at] != Opcode.CHANNEL:
        at += 9 + struct.unpack_from("<Q", data, at + 1)[0]
    data[at] = 0x7F
    path.write_bytes(bytes(data))


def bomb_log(path: Path, compression: str, inflated_bytes: int, declared_bytes: int,
             chunks: int = 1) -> None:
    """A finished log of ``chunks`` chunks, each inflating to ``inflated_bytes`` (one
    /servo/state message of zeros at log time 1 ns) and declaring ``declared_bytes``;
    summary and index included. Each chunk says it starts at 0 ns, so a reader in log
    time order reads them all before it can yield the first message."""
    message = struct.pack("<BQHIQQ", Opcode.MESSAGE, inflated_bytes - 9, 1, 1, 1, 1)
    zeros = bytes(MIB)
    n_mib, rest = divmod(inflated_bytes - len(message), MIB)
    if compression == "zstd":
        compressor = zstandard.ZstdCompressor(level=1).compressobj(size=inflated_bytes)
        data = compressor.compress(message) + b"".join(
            compressor.compress(zeros) for _ in range(n_mib)) + compressor.compress(
            bytes(rest)) + compressor.flush()
    else:
        lz4_frame = lz4.frame.LZ4FrameCompressor()
        data = lz4_frame.begin() + lz4_frame.compress(message) + b"".join(
            lz4_frame.compress(zeros) for _ in range(n_mib)) + lz4_frame.compress(
            bytes(rest)) + lz4_frame.flush()
    chunk = Chunk(compression=compression, data=data, message_start_time=0,
                  message_end_time=1, uncompressed_crc=0, uncompressed_size=declared_bytes)
    path.write_bytes(_mcap_with_chunks([chunk] * chunks))


def _mcap_with_chunks(chunks: Sequence[Chunk]) -> bytes:
    schema = Schema(id=1, name="vmnav.ServoState", encoding="jsonschema", data=b"{}")
    channel = Channel(id=1, topic=topics.SERVO_STATE, message_encoding="json", schema_id=1,
                      metadata={})
    out = RecordBuilder()
    out.write(_MCAP_MAGIC)
    Header(profile="", library="tools.bench.hostile_files").write(out)
    schema.write(out)
    channel.write(out)
    indexes = []
    for chunk in chunks:
        offset = out.count
        chunk.write(out)
        indexes.append(ChunkIndex(
            message_start_time=0, message_end_time=1, chunk_start_offset=offset,
            chunk_length=out.count - offset, message_index_offsets={1: 0},
            message_index_length=0, compression=chunk.compression,
            compressed_size=len(chunk.data), uncompressed_size=chunk.uncompressed_size))
    DataEnd(0).write(out)
    summary_start = out.count
    schema.write(out)
    channel.write(out)
    for index in indexes:
        index.write(out)
    Statistics(message_count=len(chunks), schema_count=1, channel_count=1, attachment_count=0,
               metadata_count=0, chunk_count=len(chunks), message_start_time=1,
               message_end_time=1, channel_message_counts={1: len(chunks)}).write(out)
    Footer(summary_start=summary_start, summary_offset_start=0, summary_crc=0).write(out)
    out.write(_MCAP_MAGIC)
    return out.end()


def write_valid_log_to(path: Path, compression: str) -> None:
    """:func:`write_valid_log`, moved to ``path``."""
    with tempfile.TemporaryDirectory(dir=path.parent) as folder:
        os.replace(write_valid_log(Path(folder), compression), path)


def zstd_log_declaring_2_63(path: Path) -> None:
    """A valid zstd log whose first chunk declares 2^63 bytes (was: OverflowError)."""
    write_valid_log_to(path, "zstd")
    chunk_declaring(path, 2**63)


def log_with_corrupt_summary(path: Path) -> None:
    """A valid lz4 log whose summary lost its Channel record (was: KeyError)."""
    write_valid_log_to(path, "lz4")
    corrupt_summary_channel(path)


LOG_CASES: dict[str, Callable[[Path], None]] = {
    "zstd_chunk_declaring_2^63_bytes": zstd_log_declaring_2_63,
    "zstd_bomb_1gib": lambda path: bomb_log(path, "zstd", 2**30, 2**30),
    "lz4_bomb_1gib_declared_1mib": lambda path: bomb_log(path, "lz4", 2**30, MIB),
    "zstd_64_chunks_of_60mib": lambda path: bomb_log(path, "zstd", 60 * MIB, 60 * MIB,
                                                     chunks=64),
    "corrupt_summary_opcode": log_with_corrupt_summary,
}
"""Name -> writes that hostile log at the path given."""

# -- running the real commands ----------------------------------------------------------

#: The child: ``vmnav`` with its argv, then its peak resident memory (``VmHWM``, kB) into
#: the file ``sys.argv[1]`` (:mod:`tools.bench.memory_status` says why not ``ru_maxrss``).
_CHILD = """import sys
from pathlib import Path
from tools.bench.memory_status import status_kb
from tools.cli import main
try:
    code = main(sys.argv[2:])
finally:
    Path(sys.argv[1]).write_text(str(status_kb("VmHWM")))
sys.exit(code)
"""


@dataclass(frozen=True)
class Run:
    """One command on one hostile file, in a fresh process.

    Attributes:
        peak_rss_mb: the child's peak resident memory, MB (its ``VmHWM``; ``ru_maxrss``
            if it did not end by itself).
        time_s: wall time, s.
        exit_code: its exit code (negative: killed by that signal; None: hung).
        stderr: what it wrote on stderr.
        stdout: what it wrote on stdout.
    """

    peak_rss_mb: float
    time_s: float
    exit_code: int | None
    stderr: str
    stdout: str

    @property
    def traceback(self) -> bool:
        """It printed a Python traceback."""
        return "Traceback" in self.stderr

    @property
    def refused_one_line(self) -> bool:
        """Exit 1 with exactly one line on stderr, ``vmnav ...: error: ...``."""
        lines = self.stderr.strip().splitlines()
        return self.exit_code == 1 and len(lines) == 1 and ": error: " in lines[0]


def run_command(argv: Sequence[str], workdir: Path) -> Run:
    """``vmnav *argv`` in a child process; its peak RSS (:data:`_CHILD`)."""
    out_path, err_path = workdir / "stdout.txt", workdir / "stderr.txt"
    peak_path = workdir / "peak_kb.txt"
    peak_path.unlink(missing_ok=True)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    start = time.perf_counter()
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        child = subprocess.Popen([sys.executable, "-c", _CHILD, str(peak_path), *argv],
                                 stdout=out, stderr=err, env=env, cwd=workdir)
    exit_code: int | None = None
    while True:
        pid, status, usage = os.wait4(child.pid, os.WNOHANG)
        if pid:
            exit_code = os.waitstatus_to_exitcode(status)
            break
        if time.perf_counter() - start > RUN_TIMEOUT_S:
            child.kill()
            _, status, usage = os.wait4(child.pid, 0)
            break
        time.sleep(0.02)
    child.returncode = exit_code if exit_code is not None else -9
    peak_kb = int(peak_path.read_text()) if peak_path.exists() else usage.ru_maxrss
    return Run(peak_rss_mb=peak_kb * 1024 / MB, time_s=time.perf_counter() - start,
               exit_code=exit_code, stderr=err_path.read_text(errors="replace"),
               stdout=out_path.read_text(errors="replace"))


def _figures(run: Run, must_refuse: bool) -> dict[str, object]:
    handled = run.refused_one_line if must_refuse else (run.exit_code == 0
                                                        and not run.traceback)
    message = (run.stderr.strip() or run.stdout.strip()).splitlines()
    return {"peak_rss_mb": round(run.peak_rss_mb, 1), "time_s": round(run.time_s, 2),
            "exit_code": run.exit_code, "refused_one_line": run.refused_one_line,
            "handled": handled,
            "message": next((line for line in message if "error" in line or "damaged" in line),
                            message[0] if message else "")[:200]}


def measure(seed: int = 0) -> dict[str, object]:
    """Every case of :data:`MEMORY_CASES` through ``vmnav memory info``, every case of
    :data:`LOG_CASES` through ``vmnav log info``, ``log plot`` and ``log recover``.

    Takes about 30 s on an idle machine: 19 child processes of about 1 s each (mostly
    imports) and building the 1 GiB log bombs (2.5 min on a loaded 2-core machine).

    Returns:
        ``{"runs": {"<case> <command>": {peak_rss_mb, time_s, exit_code,
        refused_one_line, handled, message}}, "max_peak_rss_mb", "all_handled",
        "targets_met"}``; ``handled``: refused with one line (memory info, log plot), or
        exit 0 without a traceback (log info and log recover, which report what is
        damaged and skip it).
    """
    runs: dict[str, dict[str, object]] = {}
    with tempfile.TemporaryDirectory(prefix="vmnav-hostile-") as tmp:
        root = Path(tmp)
        valid = root / "valid-memory"
        write_valid_memory(valid, seed)
        for name, damage in MEMORY_CASES.items():
            directory = root / name
            shutil.copytree(valid, directory)
            damage(directory)
            runs[f"{name} memory info"] = _figures(
                run_command(["memory", "info", "--memory", str(directory)], root), must_refuse=True)
            shutil.rmtree(directory)
        for name, write in LOG_CASES.items():
            path = root / "hostile.mcap"
            write(path)
            for command, must_refuse in (("info", False), ("plot", True), ("recover", False)):
                argv = ["log", command, str(path)]
                if command == "plot":
                    argv += ["--out", str(root)]
                if command == "recover":
                    argv += ["-o", str(root / "recovered.mcap")]
                runs[f"{name} log {command}"] = _figures(run_command(argv, root), must_refuse)
            path.unlink()
    peak = max(float(r["peak_rss_mb"]) for r in runs.values())  # type: ignore[arg-type]
    all_handled = all(bool(r["handled"]) for r in runs.values())
    return {"runs": runs, "max_peak_rss_mb": peak, "all_handled": all_handled,
            "targets_met": all_handled and peak < MAX_RSS_MB}
