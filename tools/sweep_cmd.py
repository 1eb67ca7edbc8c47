"""``vmnav sweep run PLAN.toml`` and ``vmnav sweep report RESULTS``: many simulated repeats
over the axes of a plan, on the local cores or on Ray, and their report (docs/sweeps.md).

The sweep's code is :mod:`tools.sweep`; this module declares the command lines.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from shared.errors import InputError
from tools.harness.arg_types import POSITIVE_COUNT


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav sweep run`` and ``vmnav sweep report``."""
    sweep = subparsers.add_parser("sweep", help="many simulated repeats over a plan's axes, "
                                  "on every core or on Ray, and their report")
    sub = sweep.add_subparsers(dest="sweep_command", metavar="ACTION", required=True)
    run = sub.add_parser(
        "run", help="run a plan's cases (resumes an interrupted sweep)",
        description="Check the plan (every axis value, world, camera file and scene change), "
        "then teach each (world, seed, camera) memory once and repeat every case on it, on "
        "a pool of local processes or on Ray. One row per case is appended to "
        "OUT/results.csv as it ends (with the plan in OUT/sweep.json and the code version), "
        "so running the same command again resumes; a case that crashes is a row with its "
        "traceback.")
    run.add_argument("plan", type=Path, metavar="PLAN.toml", help="the plan (docs/sweeps.md)")
    run.add_argument("--out", type=Path, metavar="DIR",
                     help="the sweep's folder: results, memories [default: out/sweep/PLAN]")
    run.add_argument("--workers", type=POSITIVE_COUNT, default=None, metavar="N",
                     help="local processes (with --ray local: Ray's CPUs) [default: one per "
                     "CPU]")
    run.add_argument("--cases", type=POSITIVE_COUNT, default=None, metavar="N",
                     help="run the plan's first N cases only (the same command without it "
                     "runs the rest later) [default: all]")
    run.add_argument("--ray", metavar="local|auto|ADDRESS",
                     help="run on Ray: 'local' starts it on this machine, 'auto' joins the "
                     "cluster started here with 'ray start', or a cluster's address "
                     "(pip install 'vmnav[ray]')")
    run.set_defaults(run=run_sweep_command)
    report = sub.add_parser(
        "report", help="write a sweep's report: Markdown with plots",
        description="Read a sweep's results and write report.md and its PNG plots: success "
        "rate per axis value with 95 %% Wilson intervals, lateral error CDFs, km per "
        "intervention with its interval, the worst cases with the command rerunning each.")
    report.add_argument("results", type=Path, metavar="RESULTS",
                        help="the sweep's folder (or its results.csv)")
    report.add_argument("--out", type=Path, metavar="DIR",
                        help="the report's folder [default: RESULTS/report]")
    report.set_defaults(run=report_command)


def run_sweep_command(args: argparse.Namespace) -> int:
    """Check the plan, then run its cases not done yet; one line per case on stderr."""
    from tools.sweep.executors import Executor, PoolExecutor, RayExecutor, cpu_count
    from tools.sweep.plan import Case, read_plan
    from tools.sweep.plan_check import check_plan
    from tools.sweep.results import MEMORIES_NAME, ResultsTable, code_version
    from tools.sweep.runner import outcome_text, run_sweep

    plan = read_plan(args.plan)
    check_plan(plan)
    cases = plan.cases()[:args.cases]
    out: Path = args.out or Path("out/sweep") / args.plan.stem
    version = code_version()
    executor: Executor = (RayExecutor(args.ray, args.workers) if args.ray is not None
                          else PoolExecutor(args.workers or cpu_count()))
    try:
        table = ResultsTable(out, plan.to_dict(), version)
    except InputError:
        executor.close()
        raise
    varying = [name for name, values in plan.axes if len(values) > 1]
    before = len(table.done)
    print(f"vmnav sweep: {len(cases)} cases, {before} done before; results in {table.path}",
          file=sys.stderr, flush=True)
    older = sum(row.get("code_version") != version for row in table.rows)
    if older:
        print(f"vmnav sweep: note: {older} of the rows done before came from another code "
              f"version than this one ({version}); they are kept", file=sys.stderr)
    count = before

    def line(case: Case, row: dict[str, object]) -> None:
        nonlocal count
        count += 1
        values = " ".join(f"{name}={row[name]}" for name in varying)
        print(f"vmnav sweep: [{count}/{len(cases)}] {case.case_id} {values}: "
              f"{outcome_text(row)}", file=sys.stderr, flush=True)

    try:
        rows = run_sweep(cases, lambda case: out / MEMORIES_NAME / case.memory_name, executor,
                         table, version, line)
    except BaseException as e:
        executor.close(abandon=True)  # the cases running are not awaited
        if isinstance(e, KeyboardInterrupt | SystemExit):  # Ctrl-C, SIGTERM
            print(f"vmnav sweep: stopped with {count} of {len(cases)} cases done (in "
                  f"{table.path}); the same command resumes, running the cases cut short "
                  "again", file=sys.stderr)
        raise
    executor.close()
    ok = [row for row in rows if row["status"] == "ok"]
    reached = sum(bool(row["reached_goal"]) for row in ok)
    print(f"{len(rows)} cases: {reached} reached the goal, {len(ok) - reached} did not, "
          f"{len(rows) - len(ok)} crashed; results in {table.path}; "
          f"report: vmnav sweep report {out}")
    return 0


def report_command(args: argparse.Namespace) -> int:
    """Write the report of a sweep's folder."""
    from tools.sweep.report import write_report
    from tools.sweep.results import PLAN_NAME, RESULTS_NAME, read_json, read_rows

    folder: Path = args.results.parent if args.results.name == RESULTS_NAME else args.results
    if not (folder / PLAN_NAME).exists():
        raise InputError(args.results, f"is not a sweep's folder (no {PLAN_NAME})")
    if not (folder / RESULTS_NAME).exists():
        raise InputError(folder, f"holds no results yet ({RESULTS_NAME})")
    plan = read_json(folder / PLAN_NAME).get("plan")
    if not isinstance(plan, dict) or not isinstance(plan.get("axes"), dict):
        raise InputError(folder / PLAN_NAME, "holds no plan")
    rows = read_rows(folder / RESULTS_NAME)
    out: Path = args.out or folder / "report"
    if out.exists() and (not out.is_dir() or (any(out.iterdir())
                                              and not (out / "report.md").exists())):
        raise InputError(out, "holds files of no report: choose a new or empty --out")
    out.mkdir(parents=True, exist_ok=True)
    planned = math.prod(len(values) for values in plan["axes"].values())
    path = write_report(rows, plan, planned, out)
    print(f"wrote {path} and its plots ({len(rows)} cases)")
    return 0
