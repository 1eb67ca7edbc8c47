"""``vmnav replay LOG.mcap --memory DIR``: rerun a field log's missions and compare.

The log's mission starts and cycles (:mod:`robot.logged_missions`) go through
:func:`robot.replay.replay` against the memory in DIR; the command prints how the
replayed estimates, commands, key image switches and states differ from the logged
ones (or JSON with ``--json``). Exit status: 0 identical within ``--tolerance``, 1
different, 2 bad input (one line on stderr: a file that is not a finished field log
with missions, a memory without the missions' goals, frames of another size, ...).
Lossy (JPEG) frames replay only approximately: a warning says so, and the
differences are reported as usual.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from shared.errors import InputError, VmnavError
from tools.harness.arg_types import NON_NEGATIVE
from tools.harness.progress import Progress

if TYPE_CHECKING:
    from robot.replay import ReplayReport

T = TypeVar("T")

#: Exit statuses.
IDENTICAL, DIFFERENT, BAD_INPUT = 0, 1, 2


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav replay``."""
    replay = subparsers.add_parser(
        "replay",
        help="rerun a field log's missions and compare with the log",
        description="Rebuild each mission of the robot field log LOG (its goal, config and "
        "random generator state), feed it the logged frames and base states, and compare "
        "per cycle y, theta, s, matches, the command, key image switches and mission states "
        "with the logged ones. A log rotated into several files is given as its files or "
        "its first file. Exit status 0 when identical within the tolerance, 1 when they "
        "differ, 2 on bad input. Exact only for logs written with [log] replay_frames = true "
        "(lossless frames); JPEG frames give an approximate replay.",
    )
    replay.add_argument("log", type=Path, nargs="+", metavar="LOG",
                        help="the robot field log (MCAP): its files, or the first of a series")
    replay.add_argument("--memory", required=True, type=Path, metavar="DIR",
                        help="the visual memory the robot used")
    replay.add_argument("--config", metavar="FILE",
                        help="replay with this vmnav TOML config instead of each mission's "
                        "logged one (to see what a parameter change does)")
    replay.add_argument("--tolerance", type=NON_NEGATIVE, default=0.0, metavar="X",
                        help="numbers closer than this are equal (absolute, in their units) "
                        "[default: 0, exact]")
    replay.add_argument("--json", action="store_true", help="print the result as JSON")
    replay.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Replay, print the result; the exit status says identical, different or bad input."""
    from robot.config import load_config
    from robot.logged_missions import check_replay_log, read_mission_starts, read_missions
    from robot.replay import replay
    from shared.logs.series import log_series, series_name
    from shared.memory import read_memory

    try:
        files = log_series(args.log)
        check_replay_log(files)
        memory = read_memory(args.memory)
        for start in read_mission_starts(files):
            if start.goal_id not in memory.keyframes:
                raise InputError(args.memory, f"has no key image {start.goal_id}, the goal of "
                                 f"the mission started at {start.t_ns / 1e9:.3f} s: replay "
                                 f"needs the memory the robot used")
        config = None if args.config is None else load_config(args.config)
        with Progress("replay") as bar:
            items = counted(read_missions(files), bar) if bar.shown else read_missions(files)
            report = replay(items, memory, config=config, tolerance=args.tolerance)
        if not report.cycles:
            raise InputError(series_name(files), f"no cycle could be replayed ({report.skipped} "
                             f"without a logged frame or base state)")
    except VmnavError as e:
        print(f"vmnav replay: error: {e}", file=sys.stderr)
        return BAD_INPUT
    for line in warnings(report):
        print(f"vmnav replay: warning: {line}", file=sys.stderr)
    if args.json:
        print(json.dumps({"files": [str(f) for f in files], **report.as_dict()}, indent=2))
    else:
        print(summary_text(report, series_name(files)))
    return IDENTICAL if report.identical else DIFFERENT


def counted(items: Iterable[T], bar: Progress) -> Iterator[T]:
    """``items``, counting them on ``bar`` (every 15th: the terminal need not see each)."""
    for n, item in enumerate(items, 1):
        if n % 15 == 0:
            bar.update(detail=f"{n} log records")
        yield item


def warnings(report: ReplayReport) -> list[str]:
    """What makes the replay less than exact, one line each."""
    lines = []
    if report.approximate:
        lines.append(f"{report.approximate} of {report.cycles} cycles were logged with lossy "
                     f"(JPEG) frames: the replay is only approximate; log with [log] "
                     f"replay_frames = true for an exact one")
    if report.skipped:
        lines.append(f"{report.skipped} cycles could not be replayed (no frame or base state "
                     f"logged, or before the first mission start)")
    if report.fed_only:
        lines.append(f"{report.fed_only} cycles were replayed but not compared (no servo "
                     f"state logged)")
    return lines


def summary_text(report: ReplayReport, log: str) -> str:
    """The result as a few lines and a table of the fields."""
    frames = ("lossless frames" if report.approximate == 0
              else f"frames, {report.approximate} of them lossy (JPEG)")
    missions = f"{report.missions} mission{'' if report.missions == 1 else 's'}"
    lines = [f"replay of {log}: {missions}, {report.cycles} cycles compared on {frames}"]
    width = max(len(name) for name in report.fields)
    lines.append(f"  {'field':<{width}}  {'mismatches':>10}  max |diff|")
    lines += [f"  {name:<{width}}  {f.mismatches:>10}  {f.max_abs_diff:.6g}"
              for name, f in report.fields.items()]
    first = report.first
    if first is None:
        lines.append(f"identical to the log (tolerance {report.tolerance:g})")
    else:
        lines.append(f"differs from the log (tolerance {report.tolerance:g}): first at "
                     f"{first.t_ns / 1e9:.3f} s (mission {first.mission}, cycle {first.cycle}): "
                     f"{first.field} logged {first.logged!r}, replayed {first.replayed!r}")
    return "\n".join(lines)
