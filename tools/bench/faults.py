"""``vmnav bench faults``: every fault case of issue 8, repeated (issue 8: "every case passes
10 times in a row").

:data:`CASES` names the cases of :mod:`tools.harness.fault_cases` and
:mod:`tools.harness.fault_garbage` in the order they run; ``tests/tools/bench/test_faults.py``
runs each once through :func:`run_case`. :func:`bench_faults` teaches the route once, then
runs each case ``repeat`` times in a row, each run in a fresh folder, and reports per case
how many runs passed and the first line of each failure.
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from tools.harness.fault_cases import (
    aria_link_cut,
    aria_link_cut_hold,
    camera_stall,
    emergency_stop,
    gcs_silent_continue,
    gcs_silent_hold,
    gcs_silent_manual,
    robot_sigkill,
)
from tools.harness.fault_garbage import (
    bad_frames,
    corrupt_memory,
    garbage_aria_client,
    garbage_aria_server,
    garbage_mavlink,
)
from tools.harness.hil_rig import Taught, teach

#: Every case by name, in the order they run.
CASES: dict[str, Callable[[Taught, Path], None]] = {
    "aria_link_cut": aria_link_cut,
    "aria_link_cut_hold": aria_link_cut_hold,
    "camera_stall": camera_stall,
    "gcs_silent_hold": gcs_silent_hold,
    "gcs_silent_continue": gcs_silent_continue,
    "gcs_silent_manual": gcs_silent_manual,
    "robot_sigkill": robot_sigkill,
    "emergency_stop": emergency_stop,
    "garbage_aria_server": garbage_aria_server,
    "garbage_aria_client": garbage_aria_client,
    "garbage_mavlink": garbage_mavlink,
    "corrupt_memory": corrupt_memory,
    "bad_frames": bad_frames,
}


def run_case(name: str, taught: Taught, folder: Path) -> None:
    """Run case ``name`` once in ``folder`` (created; it must not exist).

    Raises:
        FaultCaseError: the robot behaved otherwise than expected; any other error is the
            rig's (a port, a process) and fails the case too.
    """
    folder.mkdir(parents=True)
    CASES[name](taught, folder)


def bench_faults(names: Sequence[str], repeat: int, folder: Path,
                 progress: Callable[[str], None], keep_passed: bool = True) -> dict[str, Any]:
    """Teach once into ``folder/taught``, then run each case ``repeat`` times in a row.

    Args:
        names: cases of :data:`CASES`, in order.
        repeat: runs per case.
        folder: where the runs' folders go (``<case>-<run>``: memory, state, logs, output).
        progress: called with one line per run.
        keep_passed: keep the folders of the runs that passed (a mission run's field log
            is about 10 MB); those of failed runs are always kept.

    Returns:
        ``{case: {"passed", "runs", "failures": [first line of each], "wall_s_max"}}``.
    """
    taught = teach(folder / "taught")
    result: dict[str, Any] = {}
    for name in names:
        failures: list[str] = []
        longest_s = 0.0
        for run in range(1, repeat + 1):
            started = time.perf_counter()
            outcome = "passed"
            run_folder = folder / f"{name}-{run}"
            try:
                run_case(name, taught, run_folder)
            except Exception as e:  # a failed run is a result: report it, run the next
                lines = str(e).strip().splitlines()
                outcome = f"{type(e).__name__}: {lines[0] if lines else ''}"
                failures.append(f"run {run}: {outcome}")
            else:
                if not keep_passed:
                    shutil.rmtree(run_folder)
            wall_s = time.perf_counter() - started
            longest_s = max(longest_s, wall_s)
            progress(f"{name} run {run}/{repeat} in {wall_s:.1f} s: {outcome}")
        result[name] = {"passed": repeat - len(failures), "runs": repeat, "failures": failures,
                        "wall_s_max": round(longest_s, 1)}
    return result


def run(args: argparse.Namespace) -> int:
    """Print the fault benchmark's JSON (``vmnav bench faults``; exit 0 whatever the cases
    did: the JSON says)."""
    import sys
    import tempfile

    from shared.errors import InputError
    from tools.bench.names import picked

    if args.repeat < 1:
        raise InputError("--repeat", f"must be >= 1, got {args.repeat}")
    names = list(CASES) if args.cases is None else picked("--cases", args.cases, list(CASES),
                                                          "case")

    def progress(line: str) -> None:
        print(f"vmnav bench faults: {line}", file=sys.stderr, flush=True)

    with tempfile.TemporaryDirectory(prefix="vmnav-faults-") as scratch:
        folder = args.out if args.out is not None else Path(scratch)
        result = bench_faults(names, args.repeat, folder, progress,
                              keep_passed=args.out is not None)
    print(json.dumps(result, indent=2))
    return 0
