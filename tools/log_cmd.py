"""``vmnav log ...``: inspect and repair MCAP field logs.

* ``vmnav log info FILE [--json]``: start date, topics, schemas, message counts, duration,
  rates; works on unfinished files too (by scanning) and says what is wrong with them.
* ``vmnav log recover FILE [-o OUT]``: rewrite an unfinished or damaged file (from a
  killed process) into a valid, indexed one; FILE is never changed.
* ``vmnav log plot FILE [--out DIR]``: the paper-style figures of a robot log
  (:mod:`tools.figures.log_plot`).
* ``vmnav log dump TLOG [OPTION ...]``: pymavlink's ``mavlogdump`` with the vmnav dialect
  (:mod:`ground.tlog_dump`), e.g. on the ground station's ``.tlog``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shared.logs.reader import LogInfo, RecoverReport


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav log`` and its subcommands."""
    log = subparsers.add_parser("log", help="inspect, recover and plot MCAP field logs")
    log_sub = log.add_subparsers(dest="log_command", metavar="SUBCOMMAND", required=True)
    info = log_sub.add_parser(
        "info",
        help="topics, schemas, message counts, duration and rates of a log",
        description="Summarise the MCAP file FILE: per topic its schema, message count and "
        "rate, and the log's duration. A finished file is read from its summary; an "
        "unfinished one (a killed writer) is scanned and what is wrong with it is shown.",
    )
    info.add_argument("file", type=Path, metavar="FILE", help="an MCAP file")
    info.add_argument("--json", action="store_true", help="print the summary as JSON")
    info.set_defaults(run=run_info)
    recover = log_sub.add_parser(
        "recover",
        help="rewrite an unfinished or damaged log into a valid, indexed one",
        description="Copy every message of every intact chunk of FILE, with schemas, "
        "channels, metadata and attachments, into a new valid MCAP file with a summary and "
        "index. FILE is only read.",
    )
    recover.add_argument("file", type=Path, metavar="FILE", help="the unfinished MCAP file")
    recover.add_argument("-o", "--output", type=Path, metavar="OUT",
                         help="the file to write [default: FILE with .recovered.mcap]")
    recover.set_defaults(run=run_recover)
    plot = log_sub.add_parser(
        "plot",
        help="the paper-style figures of a robot log (y, theta, image errors, matches)",
        description="From the servo state and odometry of the finished MCAP file FILE, write "
        "y and theta against the distance driven, errImageMax and errPoints against time, "
        "and the matches per frame, as PNG files named after FILE.",
    )
    plot.add_argument("file", type=Path, metavar="FILE", help="a robot log (MCAP)")
    plot.add_argument("--out", type=Path, metavar="DIR",
                      help="folder of the figures [default: FILE's folder]")
    plot.set_defaults(run=run_plot)
    dump = log_sub.add_parser(
        "dump",
        help="print a MAVLink telemetry log (.tlog) with the vmnav dialect (mavlogdump)",
        description="Run pymavlink's mavlogdump on TLOG with the vmnav dialect loaded, so "
        "that vmnav's messages (VISUAL_SERVO_STATUS, ...) print by name instead of "
        "UNKNOWN_24400. Options after TLOG go to mavlogdump as they are, e.g. "
        "--types VISUAL_SERVO_STATUS, --format json, --show-types.",
    )
    dump.add_argument("file", type=Path, metavar="TLOG",
                      help="a telemetry log, e.g. the ground station's ground-*.tlog")
    dump.add_argument("options", nargs=argparse.REMAINDER, metavar="OPTION",
                      help="mavlogdump's options (see mavlogdump.py --help)")
    dump.set_defaults(run=run_dump)


def run_info(args: argparse.Namespace) -> int:
    """Print the summary of ``args.file``."""
    from shared.logs.reader import log_info

    info = log_info(args.file)
    print(json.dumps(info.as_dict(), indent=2) if args.json else info_text(info))
    return 0


def info_text(info: LogInfo) -> str:
    """The summary as a readable table."""
    status = "complete (summary and index)" if info.complete else (
        f"{info.problem}; `vmnav log recover {info.path}` rewrites it into a valid file")
    lines = [
        f"file      {info.path} ({info.size_bytes / 1e6:.1f} MB, written by "
        f"{info.library or 'an unnamed library'})",
        f"status    {status}",
        f"duration  {info.duration_s:.2f} s, {info.message_count} messages"
        + (f", metadata: {', '.join(info.metadata)}" if info.metadata else ""),
    ]
    if info.start_ns is not None:
        lines.append(f"started   {start_text(info.start_ns, info.unix_offset_ns)}")
    if not info.topics:
        return "\n".join([*lines, "no topics"])
    width = max(len("topic"), *(len(t.topic) for t in info.topics))
    schema_width = max(len("schema"), *(len(t.schema_name) for t in info.topics))
    lines.append(f"{'topic':<{width}}  {'schema':<{schema_width}}  {'messages':>8}  "
                 f"{'rate Hz':>8}")
    lines += [f"{t.topic:<{width}}  {t.schema_name:<{schema_width}}  {t.message_count:>8}  "
              f"{t.rate_hz:>8.2f}" for t in info.topics]
    return "\n".join(lines)


def start_text(start_ns: int, unix_offset_ns: int | None) -> str:
    """When a log starts: its UTC date and the writer's clock then, or for a log that
    recorded no Unix offset (written before logs were in Unix time), the clock alone."""
    if unix_offset_ns is None:
        return f"{start_ns / 1e9:.3f} s on the writer's clock (no date recorded)"
    seconds, ns = divmod(start_ns, 1_000_000_000)
    date = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(seconds))
    return (f"{date}.{ns // 1_000_000:03d} UTC (the writer's clock: "
            f"{(start_ns - unix_offset_ns) / 1e9:.3f} s)")


def default_output(path: Path) -> Path:
    """``run.mcap`` -> ``run.recovered.mcap`` (any other name gets the suffix appended)."""
    stem = path.name[: -len(".mcap")] if path.name.endswith(".mcap") else path.name
    return path.with_name(f"{stem}.recovered.mcap")


def run_recover(args: argparse.Namespace) -> int:
    """Recover ``args.file`` into ``args.output`` and say what was kept."""
    from shared.logs.reader import recover

    report = recover(args.file, args.output or default_output(args.file))
    print(recover_text(report))
    return 0


def run_plot(args: argparse.Namespace) -> int:
    """Write the figures of ``args.file`` and list them."""
    from tools.figures.log_plot import plot_log

    for path in plot_log(args.file, args.out):
        print(f"wrote {path}")
    return 0


def run_dump(args: argparse.Namespace) -> int:
    """Print ``args.file`` with pymavlink's mavlogdump and our dialect."""
    from ground.tlog_dump import run_mavlogdump
    from shared.errors import InputError

    if not args.file.is_file():
        raise InputError(args.file, "no such file" if not args.file.exists() else "not a file")
    return run_mavlogdump([*args.options, str(args.file)])


def recover_text(report: RecoverReport) -> str:
    """What :func:`~shared.logs.reader.recover` kept, in a few lines."""
    span = ("" if report.start_ns is None or report.end_ns is None
            else f", {(report.end_ns - report.start_ns) / 1e9:.2f} s")
    lines = [f"wrote {report.dst}: {report.messages} messages on {report.topics} topics{span}"]
    if report.source_complete:
        lines.append(f"{report.src} was already complete; the copy holds the same messages")
    else:
        lines.append(f"{report.src}: {report.problem or 'no summary or index'}")
    if report.skipped_chunks:
        lines.append(f"skipped {report.skipped_chunks} damaged chunk(s)")
    if report.orphaned:
        lines.append(f"left out {report.orphaned} message(s) whose channel was in a damaged chunk")
    return "\n".join(lines)
