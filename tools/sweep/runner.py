"""Run a sweep's cases on an executor: teach each memory once, then repeat its cases.

The loop (the only code here that waits):

1. Cases with a row in the results table are done (resumption); the others are grouped by
   the memory they repeat on (:attr:`tools.sweep.plan.Case.memory_name`).
2. One teach task per memory, so no two workers ever teach the same memory; a memory
   taught before is found in its folder and reused. At most as many teaches are in
   flight as the executor runs tasks at once, in the plan's order.
3. When a memory's teach ends, its cases are submitted, then the next memory's teach:
   rows come as the sweep goes, not only once every memory is taught (a 1,008-case plan
   teaches 56 memories, hours of work), and a sweep stopped early has the rows of the
   time it ran. A teach that fails fails each of its cases with the teach's traceback.
4. Each case's row is appended to the table as it ends (whatever the order), with the
   code version, the case's options and its memory's teach time (the time to find it
   when it was taught before); a case that crashed (or whose worker died) is a
   row with status ``crashed`` and its traceback, and the sweep goes on.
"""

from __future__ import annotations

import shlex
import traceback
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from pathlib import Path
from typing import Any

from tools.harness.progress import Progress
from tools.sweep.case import case_task, teach_task
from tools.sweep.executors import Executor
from tools.sweep.plan import Case
from tools.sweep.results import ResultsTable

Row = dict[str, Any]


def run_sweep(cases: list[Case], memories: Callable[[Case], Path], executor: Executor,
              table: ResultsTable | None, version: str,
              on_row: Callable[[Case, Row], None] | None = None,
              description: str = "sweep") -> list[Row]:
    """Run the cases not done yet (see the module docstring).

    Args:
        cases: the plan's cases.
        memories: the folder of a case's memory (the same for cases of one memory).
        executor: where tasks run.
        table: where rows go, and which cases are done; None: keep rows in memory only.
        version: the code version written in each row.
        on_row: called with each new row as its case ends.
        description: the progress bar's label.

    Returns:
        The row of every case, in the order of ``cases`` (rows read from the table too).
    """
    rows: dict[str, Row] = {} if table is None else {str(r["case_id"]): r for r in table.rows}
    todo = [case for case in cases if case.case_id not in rows]
    groups: dict[Path, list[Case]] = {}
    for case in todo:
        groups.setdefault(memories(case), []).append(case)
    failed = 0

    def record(case: Case, result: Row) -> None:
        nonlocal failed
        row = {"case_id": case.case_id, **dict(case.values), **result,
               "code_version": version, "options": shlex.join(case.argv)}
        failed += row["status"] != "ok"
        if table is not None:
            table.append(row)
        rows[case.case_id] = row
        if on_row is not None:
            on_row(case, row)

    processes = executor.teach_processes(len(groups))
    teaches: dict[Future[Any], Path] = {}
    running: dict[Future[Any], tuple[Case, float | None]] = {}
    untaught = list(groups.items())
    pending: set[Future[Any]] = set()

    def teach_next() -> None:
        folder, group = untaught.pop(0)
        future = _submit(executor, teach_task, group[0].run_memory_argv, folder, processes,
                         executor.render_threads)
        teaches[future] = folder
        pending.add(future)

    with Progress(f"{description} on {executor.description}", len(todo)) as bar:
        bar.update(0, f"teaching {len(groups)} memories")
        while untaught and len(teaches) < max(1, executor.workers):
            teach_next()
        while pending:
            finished = wait(pending, return_when=FIRST_COMPLETED).done
            pending -= finished
            for future in finished:
                result = _result(future)
                if future in running:
                    case, teach_s = running.pop(future)
                    record(case, {**result, "teach_wall_time_s": teach_s})
                    bar.update(len(rows) - (len(cases) - len(todo)),
                               f"{failed} failed" if failed else "")
                    continue
                folder = teaches.pop(future)
                for case in groups[folder]:
                    if result["status"] != "ok":
                        record(case, {"status": "crashed", "error": "teaching its memory "
                                      f"in {folder} failed:\n{result['error']}"})
                        continue
                    submitted = _submit(executor, case_task, case.run_argv, folder,
                                        executor.render_threads)
                    running[submitted] = (case, result["teach_wall_time_s"])
                    pending.add(submitted)
                if untaught:
                    teach_next()
    return [rows[case.case_id] for case in cases]


def _submit(executor: Executor, fn: Callable[..., Row], *args: Any) -> Future[Any]:
    """Submit, or a failed future when the executor cannot take it (a pool whose worker
    died)."""
    try:
        return executor.submit(fn, *args)
    except Exception as e:
        future: Future[Any] = Future()
        future.set_exception(e)
        return future


def _result(future: Future[Any]) -> Row:
    """The task's row, or a crashed row when the task did not return one (its worker
    died, Ray failed)."""
    try:
        result: Row = future.result()
    except Exception as e:
        return {"status": "crashed", "error": "".join(traceback.format_exception(e))}
    return result


def outcome_text(row: Row) -> str:
    """A case's figures in a line, e.g. ``reached, lateral RMS 1.4 cm, max 4.2 cm, ...``."""
    if row["status"] != "ok":
        lines = str(row.get("error") or "").strip().splitlines()
        return f"crashed ({lines[-1] if lines else 'no traceback'})"

    def cm(key: str) -> str:
        value = row[key]
        return "-" if not isinstance(value, int | float) else f"{100 * value:.1f} cm"

    outcome = "reached" if row["reached_goal"] else f"not reached ({row['reason']})"
    return (f"{outcome}, lateral RMS {cm('lateral_rms_m')}, max {cm('lateral_max_m')}, "
            f"final error {cm('final_position_error_m')}, {row['lost_events']} LOST, "
            f"{row['wall_time_s']} s")
