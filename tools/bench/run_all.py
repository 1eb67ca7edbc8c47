"""``vmnav bench all``: every benchmark in its own process, one JSON document, one table.

Each benchmark runs as ``python -m tools.cli bench NAME ...`` in a subprocess, one
after the other, so a crash, a hang (``timeout_s``) or an error loses only that
benchmark: it is reported with its exit code and its error line (the last line it
wrote on stderr). The figures of every benchmark that ran are checked against the
one table of targets (:mod:`tools.bench.targets`).

The document maps each benchmark to ``{"ok", "exit_code", "wall_s", "command",
"error", "figures", "result"}``: ``result`` is the benchmark's own JSON (None when
it failed) and ``figures`` its targets checked (figure, value, target, met, source).

``quick`` runs reduced sizes (:data:`QUICK_ARGS`) for a smoke run; a benchmark
registered later without an entry there runs its defaults. Durations on the 2-core
development machine (shared with other jobs): ``--quick`` measured 2 min 42 s (sim
3 s, vision 57 s, follow 92 s = one lab teach of about 60 s plus one 30 s repeat,
log 3 s, link 8 s). The full run is estimated from those parts at about 42 min:
follow 20 seeds x (teach 60 s + two laws x 30 s) = 40 min, vision about 1.5 min,
link 20 s, log 10 s, sim 5 s. Follow caches each seed's memory in ``OUT/follow``,
so a second full run takes about 22 min. ``faults`` (issue 8) adds about 2 min per
repetition of its cases: one with ``--quick``, ten in the full run (measured 20 min).
``fuzz`` (issue 15) adds about 30 s with ``--quick`` (1,000 inputs per target) and
about 16 min in the full run (100,000 per target; docs/fuzzing.md); ``hostile``
about 2 min in both (it has no reduced size); ``real`` (issue 16) about 20 s (15 s with
``--quick``: 3 timed pairs instead of 10); ``foxglove`` (issue 18) 4 x 5 s (4 x 2 s with
``--quick``); ``web`` (issue 18) about 45 s; ``sweep`` (issue 20) about 7.5 min measured
(20 cases on 1 and 2 workers and Ray, 5 memories taught) and about 2 min with ``--quick``
(4 cases, 1 memory; estimated).
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tools.bench.targets import DEFAULT_LAW, Check, check, targets_of

#: Reduced sizes of ``--quick``, per benchmark.
QUICK_ARGS: dict[str, tuple[str, ...]] = {
    "sim": ("--frames", "30"),
    "vision": ("--quick",),
    "follow": ("--seeds", "1", "--laws", DEFAULT_LAW),
    "log": ("--seconds", "2"),
    "link": ("--window-s", "2", "--dispatches", "50"),
    "faults": ("--repeat", "1"),
    "fuzz": ("--inputs", "1000"),
    "real": ("--repeats", "3"),
    "safety": ("--seeds", "1", "--worlds", "lab", "--estops", "4"),
    "foxglove": ("--seconds", "2"),
    "web": ("--changes", "10", "--dispatches", "10"),
    "sweep": ("--cases", "4"),
}
#: Exit codes of ``vmnav bench all`` beyond 0 (all ran, every target met).
EXIT_BENCH_FAILED = 1
EXIT_TARGET_MISSED = 3


@dataclass(frozen=True, slots=True)
class BenchRun:
    """One benchmark's run.

    Attributes:
        name: the ``vmnav bench`` name.
        arguments: the arguments after ``vmnav bench NAME``.
        exit_code: the process's exit code (negative: killed by that signal); None if
            it timed out.
        wall_s: its wall time, s.
        result: its JSON; None when it failed.
        error: why it failed (one line); None when it ran.
    """

    name: str
    arguments: tuple[str, ...]
    exit_code: int | None
    wall_s: float
    result: dict[str, Any] | None
    error: str | None

    @property
    def ok(self) -> bool:
        """It exited 0 and printed a JSON object."""
        return self.error is None

    @property
    def command(self) -> str:
        """The command line that reproduces it."""
        return shlex.join(["vmnav", "bench", self.name, *self.arguments])

    def checks(self) -> list[Check]:
        """Its targets checked against its JSON (none met when it failed)."""
        return [check(t, self.result or {}) for t in targets_of(self.name)]


def bench_arguments(name: str, quick: bool, out_dir: Path) -> list[str]:
    """The arguments ``bench all`` gives benchmark ``name``: the quick sizes, and for
    ``follow`` and ``sweep`` their memory caches under ``out_dir`` (follow's one per size:
    the cache is keyed by routes and refuses others)."""
    arguments = list(QUICK_ARGS.get(name, ())) if quick else []
    if name == "follow":
        arguments += ["--out", str(out_dir / ("follow-quick" if quick else "follow"))]
    if name == "sweep":
        arguments += ["--out", str(out_dir / "sweep")]
    return arguments


def run_benchmark(name: str, arguments: Sequence[str], timeout_s: float) -> BenchRun:
    """Run ``vmnav bench NAME ARGUMENTS`` in a subprocess (this interpreter, this
    working directory) and collect its JSON or its error line."""
    command = [sys.executable, "-m", "tools.cli", "bench", name, *arguments]
    started = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s,
                              check=False)
    except subprocess.TimeoutExpired:
        return BenchRun(name, tuple(arguments), None, time.perf_counter() - started, None,
                        f"timed out after {timeout_s:g} s")
    wall_s = time.perf_counter() - started
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        last = lines[-1].strip() if lines else "no message"
        how = (f"killed by signal {-done.returncode}" if done.returncode < 0
               else f"exit {done.returncode}")
        return BenchRun(name, tuple(arguments), done.returncode, wall_s, None, f"{how}: {last}")
    try:
        result = json.loads(done.stdout)
    except json.JSONDecodeError as e:
        return BenchRun(name, tuple(arguments), 0, wall_s, None, f"printed no JSON ({e})")
    if not isinstance(result, dict):
        return BenchRun(name, tuple(arguments), 0, wall_s, None, "printed JSON that is no object")
    return BenchRun(name, tuple(arguments), 0, wall_s, result, None)


def run_all(names: Sequence[str], quick: bool, out_dir: Path,
            extra: Mapping[str, Sequence[str]], timeout_s: float,
            progress: Callable[[str], None]) -> list[BenchRun]:
    """Run the benchmarks ``names`` in order.

    Args:
        names: ``vmnav bench`` names.
        quick: reduced sizes (:data:`QUICK_ARGS`).
        out_dir: where caches go (``follow``'s memories).
        extra: name -> arguments appended after the ones ``bench all`` gives (the last
            of a repeated option wins).
        timeout_s: each benchmark's time limit, s.
        progress: called with one line as each benchmark starts and ends.
    """
    runs = []
    for name in names:
        arguments = bench_arguments(name, quick, out_dir) + list(extra.get(name, ()))
        progress(f"running {shlex.join(['vmnav', 'bench', name, *arguments])}")
        run = run_benchmark(name, arguments, timeout_s)
        progress(f"{name}: {'ran' if run.ok else 'FAILED'} in {run.wall_s:.1f} s"
                 + (f" ({run.error})" if run.error else ""))
        runs.append(run)
    return runs


def exit_code(runs: Sequence[BenchRun]) -> int:
    """0: every benchmark ran and met its targets; :data:`EXIT_BENCH_FAILED`: one failed;
    :data:`EXIT_TARGET_MISSED`: all ran, a figure missed its target (or is missing)."""
    if not all(run.ok for run in runs):
        return EXIT_BENCH_FAILED
    if not all(c.met for run in runs for c in run.checks()):
        return EXIT_TARGET_MISSED
    return 0


def document(runs: Sequence[BenchRun]) -> dict[str, Any]:
    """The JSON document: benchmark -> its entry (module docstring)."""
    return {run.name: {
        "ok": run.ok, "exit_code": run.exit_code, "wall_s": round(run.wall_s, 1),
        "command": run.command, "error": run.error,
        "figures": [{"figure": c.target.figure, "value": c.value, "target": _target_text(c),
                     "met": c.met, "source": c.target.source} for c in run.checks()],
        "result": run.result,
    } for run in runs}


def markdown_table(runs: Sequence[BenchRun]) -> str:
    """One row per figure with a target (benchmark, figure, value, target, pass/fail); a
    failed benchmark is one FAIL row with its error; one without targets, one row."""
    rows = ["| benchmark | figure | value | target | result |", "|---|---|---|---|---|"]
    for run in runs:
        if not run.ok:
            rows.append(f"| {run.name} | (did not run) | {_cell(run.error or '')} | | FAIL |")
            continue
        checks = run.checks()
        if not checks:
            rows.append(f"| {run.name} | (no targets) | ran in {run.wall_s:.1f} s | | - |")
        for c in checks:
            value = "missing" if c.value is None else f"{c.value:.4g}"
            rows.append(f"| {run.name} | {c.target.figure} | {value} | {_target_text(c)} | "
                        f"{'pass' if c.met else 'FAIL'} |")
    return "\n".join(rows)


def _target_text(c: Check) -> str:
    """The target, with a bound taken from another figure resolved (``>= 20 (runs)``)."""
    if not isinstance(c.target.bound, str):
        return c.target.text
    name = c.target.bound.rpartition(".")[2]
    resolved = "?" if c.bound is None else f"{c.bound:g}"
    return f"{c.target.comparison} {resolved} ({name})"


def _cell(text: str) -> str:
    """``text`` safe inside a markdown table cell."""
    return text.replace("|", "\\|")


def run(args: argparse.Namespace) -> int:
    """Run every benchmark; print the document and the table; write both into ``--out``
    (``vmnav bench all``; ``args.registry``: the ``vmnav bench`` subparsers by name)."""
    from shared.atomic_file import write_text_atomic
    from shared.errors import InputError
    from tools.bench.names import picked

    known = [name for name in args.registry if name != "all"]
    names = known if args.only is None else picked("--only", args.only, known, "benchmark")
    extra: dict[str, list[str]] = {}
    for item in args.bench_args:
        name, sep, rest = item.partition("=")
        if not sep or name not in known:
            raise InputError("--bench-args", f"{item!r} is not NAME=ARGS with NAME one of "
                             f"{', '.join(known)}")
        extra.setdefault(name, []).extend(shlex.split(rest))
    if not args.timeout_s > 0:
        raise InputError("--timeout-s", f"must be > 0, got {args.timeout_s}")
    runs = run_all(names, args.quick, args.out, extra, args.timeout_s,
                   lambda line: print(f"vmnav bench all: {line}", file=sys.stderr))
    text, table = json.dumps(document(runs), indent=2), markdown_table(runs)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out / "bench_all.json", text + "\n")
    write_text_atomic(args.out / "bench_all.md", table + "\n")
    print(text)
    print()
    print(table)
    return exit_code(runs)
