"""``vmnav bench fuzz``: seeded fuzzing of every decoder and loader, crashes and hangs counted.

Each target (:mod:`tools.bench.fuzz_targets`) runs in a worker process of its own,
built once in a scratch folder, and takes its inputs one after the other. Input ``i``
of a target is a pure function of (``--seed``, target name, ``i``), so any input the
JSON reports can be made again (:func:`fuzz_input`).

* A **crash** is any exception other than the target's ``allowed`` ones (the project's
  :class:`~shared.errors.InputError`), or the worker dying (a signal, the memory limit
  hit below Python). It is counted, its kind (exception type and the innermost frame in
  the project) tallied, and the first of each kind is reported with its input (hex,
  truncated).
* A **hang** is an input still running after ``time_limit_s``. The parent watches the
  worker through shared memory (the index of the input in progress, when it began, and
  its first bytes); on a hang it kills the worker, reports the input, and starts a new
  worker at the next input.
* The worker's address space is limited (``memory_limit_mb``, ``RLIMIT_AS``), so a
  decompression bomb fails as a crash (``MemoryError``, ``cv2.error``) instead of
  swapping the machine.

The JSON: per target ``inputs``, ``crashes``, ``hangs``, ``max_input_ms``, ``wall_s``,
``cpu_s`` (the workers' CPU time: the run's length on one free core), ``worker_starts``,
``crash_kinds`` (kind -> count), ``first_crashes`` and ``hang_inputs``; totals at the
top. Timing on the 2-core development machine shared with other jobs: see
``docs/fuzzing.md``.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import logging
import multiprocessing
import multiprocessing.connection
import os
import resource
import tempfile
import time
import traceback
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: Input bytes kept for reports (hex), and by the watchdog for a hang.
REPORT_BYTES = 96
#: Crashing inputs reported per target, the first of each kind (all are counted).
REPORTED_CRASHES = 10
#: Every target, in the order they run (the keys of ``fuzz_targets.FACTORIES``, named here
#: so that the targets table need not import the targets).
TARGET_NAMES = ("aria_robot", "aria_host", "mavlink_unsigned", "mavlink_signed", "memory",
                "mcap_info", "mcap_read", "mcap_recover", "photo")
#: Where the targets' scratch folders go: memory-backed when the machine has /dev/shm, so
#: that 100,000 file writes (and the fsyncs of ``recover``) do not wait on a disk.
SCRATCH = "/dev/shm" if Path("/dev/shm").is_dir() else None
#: Longest a worker may take to build its target before its first input, s.
SETUP_LIMIT_S = 300.0
#: How often the parent checks on the worker, s.
WATCH_PERIOD_S = 0.05
#: Project folders: the innermost frame in one of them names a crash's place, unless it
#: is generated code (the MAVLink dialect: its caller says more).
_PROJECT = ("shared", "robot", "ground", "sim", "tools", "tests")
_GENERATED = (Path("shared/mavlink/vmnav_dialect.py"),)
_ROOT = Path(__file__).resolve().parents[2]


def input_rng(seed: int, target: str, index: int) -> np.random.Generator:
    """The random generator of input ``index`` of ``target`` (module docstring)."""
    return np.random.default_rng((seed, zlib.crc32(target.encode()), index))


def fuzz_input(target: str, seed: int, index: int, work: Path) -> bytes:
    """Input ``index`` of ``target`` under ``seed``, made again (the target is built in
    ``work``, a scratch folder)."""
    from tools.bench.fuzz_targets import FACTORIES

    return FACTORIES[target](work).generate(input_rng(seed, target, index))


def crash_kind(error: BaseException) -> str:
    """``"ExceptionType at path/in/project.py:LINE"`` (the innermost frame of the project
    not in generated code)."""
    place = "?"
    for frame in traceback.extract_tb(error.__traceback__):
        path = Path(frame.filename).resolve()
        if not path.is_relative_to(_ROOT):
            continue
        where = path.relative_to(_ROOT)
        if where.parts[0] in _PROJECT and where not in _GENERATED:
            place = f"{where}:{frame.lineno}"
    return f"{type(error).__name__} at {place}"


@dataclass
class TargetReport:
    """What fuzzing one target found (the module docstring's JSON, per target)."""

    inputs: int = 0
    crashes: int = 0
    hangs: int = 0
    max_input_ms: float = 0.0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    worker_starts: int = 0
    crash_kinds: dict[str, int] = field(default_factory=dict)
    first_crashes: list[dict[str, Any]] = field(default_factory=list)
    hang_inputs: list[dict[str, Any]] = field(default_factory=list)

    def add_crash(self, index: int, kind: str, line: str, data: bytes, length: int) -> None:
        """Count a crash of input ``index`` (``data``: its first bytes, ``length`` long)."""
        self.crashes += 1
        self.crash_kinds[kind] = self.crash_kinds.get(kind, 0) + 1
        if self.crash_kinds[kind] == 1 and len(self.first_crashes) < REPORTED_CRASHES:
            self.first_crashes.append({"index": index, "kind": kind, "error": line[:300],
                                       "input_len": length, "input_hex": data.hex()})


class _Shared(ctypes.Structure):
    """What the worker publishes for the watchdog: the input in progress."""

    _fields_ = [("index", ctypes.c_int64), ("start_ns", ctypes.c_int64),
                ("length", ctypes.c_int64), ("head", ctypes.c_ubyte * REPORT_BYTES)]


def _worker(target: str, seed: int, first: int, end: int, memory_limit_mb: int, work: Path,
            shared: Any, conn: multiprocessing.connection.Connection) -> None:
    """Run inputs ``first`` .. ``end - 1`` of ``target`` (built in ``work``); send crashes
    and the end stats."""
    from tools.bench.fuzz_targets import FACTORIES

    logging.disable(logging.CRITICAL)  # the targets' log lines, by the thousand
    fuzz_target = FACTORIES[target](work)
    _silence_stderr()
    limit = _address_space_bytes() + memory_limit_mb * 1024 * 1024
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    max_ns = 0
    for index in range(first, end):
        shared.length = 0
        start_ns = shared.start_ns = time.monotonic_ns()  # before the index: read after it
        shared.index = index
        try:
            data = fuzz_target.generate(input_rng(seed, target, index))
        except Exception as error:  # a bug of the bench, not of the target
            conn.send(("error", index, "".join(traceback.format_exception(error))))
            return
        head = data[:REPORT_BYTES]
        ctypes.memmove(shared.head, head, len(head))
        shared.length = len(data)
        try:
            fuzz_target.run(data)
        except fuzz_target.allowed:
            pass
        except Exception as error:  # what the fuzzer is looking for
            line = "".join(traceback.format_exception_only(error)).strip().splitlines()[-1]
            conn.send(("crash", index, crash_kind(error), line, head, len(data)))
        max_ns = max(max_ns, time.monotonic_ns() - start_ns)
    shared.index = -1
    conn.send(("done", max_ns))


def _silence_stderr() -> None:
    """Send this process's file descriptor 2 to /dev/null: libpng, libjpeg and OpenCV
    write a line there for each broken image, which the crash reports make redundant."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    os.close(devnull)


def _address_space_bytes() -> int:
    """This process's virtual memory size, bytes (Linux ``/proc/self/statm``)."""
    pages = int(Path("/proc/self/statm").read_text().split()[0])
    return pages * resource.getpagesize()


def fuzz_target(target: str, inputs: int, seed: int, time_limit_s: float,
                memory_limit_mb: int) -> TargetReport:
    """Fuzz ``target`` with ``inputs`` inputs in worker processes (module docstring)."""
    context = multiprocessing.get_context("fork")
    report = TargetReport(inputs=inputs)
    started = time.perf_counter()
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    shared = context.RawValue(_Shared)
    next_index = 0
    while next_index < inputs:
        shared.index = -1
        receiver, sender = context.Pipe(duplex=False)
        # The parent owns the scratch folder: a worker killed on a hang cannot remove it.
        with tempfile.TemporaryDirectory(prefix=f"vmnav-fuzz-{target}-", dir=SCRATCH) as tmp:
            worker = context.Process(target=_worker, name=f"fuzz-{target}", daemon=True, args=(
                target, seed, next_index, inputs, memory_limit_mb, Path(tmp), shared, sender))
            worker.start()
            sender.close()
            report.worker_starts += 1
            next_index = _watch(target, worker, receiver, shared, report, time_limit_s, inputs)
            receiver.close()
    report.wall_s = round(time.perf_counter() - started, 1)
    done = resource.getrusage(resource.RUSAGE_CHILDREN)
    report.cpu_s = round(done.ru_utime + done.ru_stime - children.ru_utime - children.ru_stime, 1)
    return report


def _watch(target: str, worker: Any, receiver: multiprocessing.connection.Connection,
           shared: _Shared, report: TargetReport, time_limit_s: float, inputs: int) -> int:
    """Follow one worker until it finishes, hangs or dies; returns the next input to run."""
    limit_ns = round(time_limit_s * 1e9)
    setup_deadline_ns: int | None = time.monotonic_ns() + round(SETUP_LIMIT_S * 1e9)
    while True:
        try:
            ready = receiver.poll(WATCH_PERIOD_S)
            message = receiver.recv() if ready else None
        except EOFError:  # the worker died: the input in progress crashed it
            worker.join()
            index = shared.index
            if index < 0:
                raise RuntimeError(f"fuzz target {target}: the worker failed before its first "
                                   f"input (exit code {worker.exitcode})") from None
            head = bytes(shared.head[:min(shared.length, REPORT_BYTES)])
            report.add_crash(index, "worker died", f"worker exit code {worker.exitcode}", head,
                             shared.length)
            return index + 1
        if message is not None and message[0] == "error":
            worker.join()
            raise RuntimeError(f"fuzz target {target}: making input {message[1]} failed:\n"
                               f"{message[2]}")
        if message is not None and message[0] == "crash":
            report.add_crash(*message[1:])
        elif message is not None:
            report.max_input_ms = max(report.max_input_ms, round(message[1] / 1e6, 2))
            worker.join()
            return inputs
        index = shared.index
        if index >= 0:
            setup_deadline_ns = None  # set up; index is -1 again once all inputs ran
        elif setup_deadline_ns is not None and time.monotonic_ns() > setup_deadline_ns:
            worker.kill()
            worker.join()
            raise RuntimeError(f"fuzz target {target}: the worker's setup took over "
                               f"{SETUP_LIMIT_S:g} s")
        if index >= 0 and time.monotonic_ns() - shared.start_ns > limit_ns:
            worker.kill()
            worker.join()
            report.hangs += 1
            report.max_input_ms = max(report.max_input_ms, time_limit_s * 1e3)
            report.hang_inputs.append({"index": index, "input_len": shared.length,
                                       "input_hex": bytes(shared.head[:min(
                                           shared.length, REPORT_BYTES)]).hex()})
            return index + 1


def bench_fuzz(targets: list[str], inputs: int, seed: int, time_limit_s: float,
               memory_limit_mb: int) -> dict[str, Any]:
    """Fuzz every target of ``targets`` in turn; the benchmark's JSON."""
    reports = {name: fuzz_target(name, inputs, seed, time_limit_s, memory_limit_mb)
               for name in targets}
    return {
        "benchmark": "fuzz", "seed": seed, "inputs_per_target": inputs,
        "time_limit_s": time_limit_s, "memory_limit_mb": memory_limit_mb,
        "crashes_total": sum(r.crashes for r in reports.values()),
        "hangs_total": sum(r.hangs for r in reports.values()),
        "targets": {name: vars(report) for name, report in reports.items()},
    }


def run(args: argparse.Namespace) -> int:
    """Print the fuzzing benchmark's JSON (``vmnav bench fuzz``)."""
    from shared.errors import InputError
    from tools.bench.names import picked

    known = list(TARGET_NAMES)
    names = known if args.targets is None else picked("--targets", args.targets, known, "target")
    if args.inputs < 1:
        raise InputError("--inputs", f"must be >= 1, got {args.inputs}")
    if not args.time_limit_s > 0:
        raise InputError("--time-limit-s", f"must be > 0, got {args.time_limit_s}")
    if args.memory_limit_mb < 256:
        raise InputError("--memory-limit-mb", f"must be >= 256, got {args.memory_limit_mb}")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_fuzz(names, args.inputs, args.seed, args.time_limit_s, args.memory_limit_mb)
    print(json.dumps({**result, "load_average_at_start": load}, indent=2))
    return 0
