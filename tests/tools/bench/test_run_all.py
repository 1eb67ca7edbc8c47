"""``vmnav bench all`` (tools/bench/run_all.py) and the table of targets (tools/bench/targets.py).

The end-to-end run is reduced to two benchmarks: ``link`` (2 vehicles, 1 s) runs,
``log`` is handed a bad argument and fails; both are real subprocesses.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import pytest

from tools.bench.run_all import (
    EXIT_BENCH_FAILED,
    EXIT_TARGET_MISSED,
    QUICK_ARGS,
    BenchRun,
    bench_arguments,
    document,
    exit_code,
    markdown_table,
    run_benchmark,
)
from tools.bench.targets import TARGETS, Target, check, figure_at, targets_of
from tools.cli import build_parser, main

HEADER = "| benchmark | figure | value | target | result |"


@pytest.fixture(scope="module")
def ran(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, str, Path]:
    """(exit code, stdout, out folder) of a quick run of link and a failing log."""
    out = tmp_path_factory.mktemp("bench_all")
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        code = main(["bench", "all", "--quick", "--only", "link,log", "--out", str(out),
                     "--bench-args", "log=--seconds 0",
                     "--bench-args", "link=--vehicles 2 --window-s 1 --dispatches 10"])
    return code, text.getvalue(), out


@pytest.mark.slow
def test_a_failed_benchmark_is_reported_and_the_others_still_run(
        ran: tuple[int, str, Path]) -> None:
    code, stdout, out = ran
    assert code == EXIT_BENCH_FAILED
    doc, end = json.JSONDecoder().raw_decode(stdout)
    assert doc == json.loads((out / "bench_all.json").read_text())
    assert list(doc) == ["link", "log"]
    log = doc["log"]
    assert (log["ok"], log["exit_code"], log["result"]) == (False, 1, None)
    assert log["error"] == "exit 1: vmnav bench: error: --seconds: must be > 0, got 0.0"
    assert log["command"] == "vmnav bench log --seconds 2 --seconds 0"
    assert [f["met"] for f in log["figures"]] == [False]
    link = doc["link"]
    assert (link["ok"], link["exit_code"], link["error"]) == (True, 0, None)
    assert link["result"]["benchmark"] == "link" and link["result"]["vehicles"] == 2
    figures = {f["figure"]: f for f in link["figures"]}
    assert set(figures) == {"dispatch_ack_ms_p95", "ground_cpu_fraction_20_vehicles"}
    assert math.isfinite(figures["dispatch_ack_ms_p95"]["value"])
    assert figures["dispatch_ack_ms_p95"]["target"] == "< 50"
    assert figures["ground_cpu_fraction_20_vehicles"]["value"] is None  # 2 vehicles only
    table = stdout[end:].strip()
    assert table == (out / "bench_all.md").read_text().strip()
    lines = table.splitlines()
    assert lines[0] == HEADER
    assert lines[2].startswith("| link | dispatch_ack_ms_p95 | ")
    assert lines[3] == "| link | ground_cpu_fraction_20_vehicles | missing | < 0.3 | FAIL |"
    assert lines[4] == ("| log | (did not run) | exit 1: vmnav bench: error: --seconds: must be "
                        "> 0, got 0.0 | | FAIL |")


@pytest.mark.parametrize("argv, message", [
    (["--only", "link,nope"],
     "--only: unknown benchmark nope (known: sim, vision, follow, sweep, log, link, faults, "
     "fuzz, hostile, real, safety, foxglove, web, chance)"),
    (["--only", ","], "--only: no benchmark"),
    (["--bench-args", "nope=--x"], "--bench-args: 'nope=--x' is not NAME=ARGS"),
    (["--timeout-s", "0"], "--timeout-s: must be > 0"),
])
def test_bad_options_are_one_line_errors(argv: list[str], message: str,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "all", *argv]) == 1
    assert message in capsys.readouterr().err


def test_a_hung_benchmark_times_out() -> None:
    run = run_benchmark("log", ["--seconds", "60"], timeout_s=1.0)
    assert (run.ok, run.exit_code, run.result) == (False, None, None)
    assert run.error == "timed out after 1 s"


def test_quick_arguments_parse_for_every_benchmark(tmp_path: Path) -> None:
    parser = build_parser()
    for name in ("sim", "vision", "follow", "sweep", "log", "link", "faults", "real",
                 "foxglove"):
        arguments = bench_arguments(name, quick=True, out_dir=tmp_path)
        assert arguments[:len(QUICK_ARGS[name])] == list(QUICK_ARGS[name])
        parser.parse_args(["bench", name, *arguments])
    assert bench_arguments("follow", quick=False, out_dir=tmp_path) == [
        "--out", str(tmp_path / "follow")]
    assert bench_arguments("sweep", quick=False, out_dir=tmp_path) == [
        "--out", str(tmp_path / "sweep")]
    assert bench_arguments("later", quick=True, out_dir=tmp_path) == []


# -- the verdicts ------------------------------------------------------------------------


def _run(name: str, result: dict | None, error: str | None = None) -> BenchRun:
    return BenchRun(name, (), 0 if error is None else 1, 1.0, result, error)


def test_the_exit_code_says_what_failed() -> None:
    met = _run("log", {"log_overhead_core_fraction": 0.05})
    missed = _run("log", {"log_overhead_core_fraction": 0.2})
    untargeted = _run("later", {"x": 1})
    failed = _run("link", None, "exit 1: boom")
    assert exit_code([met, untargeted]) == 0
    assert exit_code([met, missed]) == EXIT_TARGET_MISSED
    assert exit_code([missed, failed]) == EXIT_BENCH_FAILED


def test_the_table_has_a_row_per_figure_and_escapes_errors() -> None:
    runs = [_run("log", {"log_overhead_core_fraction": 0.2}), _run("later", {"x": 1}),
            _run("link", None, "exit 1: a | b")]
    assert markdown_table(runs).splitlines() == [
        HEADER, "|---|---|---|---|---|",
        "| log | log_overhead_core_fraction | 0.2 | < 0.1 | FAIL |",
        "| later | (no targets) | ran in 1.0 s | | - |",
        "| link | (did not run) | exit 1: a \\| b | | FAIL |"]
    assert document(runs)["later"]["figures"] == []


def test_a_bound_may_be_another_figure() -> None:
    law = next(t for t in TARGETS if t.figure.endswith(".reached_goal"))
    assert law.benchmark == "follow" and isinstance(law.bound, str)
    prefix = law.figure.split(".")[:2]
    result = {prefix[0]: {prefix[1]: {"reached_goal": 19, "runs": 20}}}
    assert check(law, result).bound == 20 and not check(law, result).met
    result[prefix[0]][prefix[1]]["reached_goal"] = 20
    assert check(law, result).met
    row = markdown_table([_run("follow", result)]).splitlines()[2]
    assert row.endswith("| 20 | >= 20 (runs) | pass |")


def test_figures_are_finite_numbers_at_a_dotted_path() -> None:
    result = {"a": {"b": 1.5, "flag": True, "nan": math.nan, "text": "x"}}
    assert figure_at(result, "a.b") == 1.5
    assert figure_at(result, "a.flag") == 1.0
    for path in ("a.nan", "a.text", "a.missing", "a.b.c", "z"):
        assert figure_at(result, path) is None
    target = Target("x", "a.nan", "<", 1.0, "test")
    assert check(target, result).met is False


def test_every_benchmark_has_targets_from_the_issues() -> None:
    for name in ("sim", "vision", "follow", "sweep", "log", "link", "faults", "real",
                 "foxglove"):
        assert targets_of(name), name
    figures = {(t.benchmark, t.figure): t.text for t in TARGETS}
    assert figures[("link", "dispatch_ack_ms_p95")] == "< 50"
    assert figures[("link", "ground_cpu_fraction_20_vehicles")] == "< 0.3"
    assert figures[("log", "log_overhead_core_fraction")] == "< 0.1"
    assert figures[("follow", "aggregate.paper+ff.lateral_rms_m_max")] == "<= 0.03"
    assert figures[("sweep", "runs.pool_2.speedup_vs_pool_1")] == ">= 1.7"
    assert figures[("follow", "aggregate.paper+ff.loop_ms_p50_median")] == "< 20"
    assert figures[("sim", "render_fps_median")] == ">= 60"
