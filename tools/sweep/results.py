"""A sweep's folder: its plan and code version (``sweep.json``) and one row per case appended
to ``results.csv`` as each case ends, so that an interrupted sweep resumes where it stopped
and a finished one is not run again.

Rules:

1. A folder is a sweep's when it holds ``sweep.json``; a sweep writes into a new or empty
   folder, or into its own with the same plan (resuming), or into a folder holding only
   ``memories/`` (memories taught by another sweep, copied to be reused: each is checked
   against what it was taught from). Another plan's folder, or a folder holding other
   files, is refused.
2. A row is written, flushed and synced when its case ends; an interrupted write leaves at
   most the last line cut short, which is dropped (and its case run again) on resumption.
   A table written before the safety figures (:data:`SAFETY_FIGURES`, the last columns)
   reads with them None, and is rewritten with them when the sweep resumes.
3. Text columns (:data:`TEXT_COLUMNS`) are stored as they are (empty: None); every other
   cell is JSON (numbers, booleans, ``null``, the scene change's object).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any

from shared.atomic_file import write_text_atomic
from shared.errors import InputError
from tools.sweep.plan import AXES

PLAN_NAME = "sweep.json"
RESULTS_NAME = "results.csv"
#: The taught memories' folder in a sweep's folder, one folder per memory.
MEMORIES_NAME = "memories"
#: The figures of a case (``tools.figures.demo_report.build_report``'s keys).
FIGURES = ("goal_key_image", "reached_goal", "reason", "final_position_error_m",
           "lateral_rms_m", "lateral_max_m", "heading_rms_deg", "key_images_route",
           "key_images_reached", "distance_m", "sim_time_s", "wall_time_s", "mean_matches",
           "loop_ms_p50", "loop_ms_p95", "lost_events", "scene_change")
#: The safety layer's figures of a case, from the simulator's truth
#: (:mod:`tools.harness.safety_truth`): waits for an obstacle, contacts with a person the
#: robot moved towards and others (a person walking into it), the longest distance driven
#: without a verified localization (m). Absent (None) in rows of sweeps run before them.
SAFETY_FIGURES = ("obstacle_waits", "contacts_moving", "contacts_still", "blind_max_m")
#: Figures measured on the wall clock: they differ from run to run, the others never.
TIMING = ("wall_time_s", "loop_ms_p50", "loop_ms_p95", "teach_wall_time_s",
          "worker_peak_rss_mb")
COLUMNS = ("case_id", "status", *AXES, *FIGURES, "teach_wall_time_s", "worker_peak_rss_mb",
           "code_version", "options", "error", *SAFETY_FIGURES)
TEXT_COLUMNS = frozenset({"case_id", "status", "world", "lighting", "removed", "doors",
                          "calibration", "law", "reason", "code_version", "options", "error"})


def code_version() -> str:
    """``vmnav VERSION tree HASH`` (12 hex digits of the sources' SHA-256), plus ``git
    DESCRIPTION`` where the sources are a git checkout."""
    root = Path(__file__).resolve().parents[2]
    digest = hashlib.sha256()
    for package in ("shared", "robot", "ground", "sim", "tools"):
        for path in sorted((root / package).rglob("*")):
            if path.suffix in (".py", ".toml", ".xml") and path.is_file():
                digest.update(str(path.relative_to(root)).encode() + b"\0")
                digest.update(path.read_bytes())
    version = f"vmnav {metadata.version('vmnav')} tree {digest.hexdigest()[:12]}"
    try:
        described = subprocess.run(["git", "-C", str(root), "describe", "--always", "--dirty"],
                                   capture_output=True, text=True, timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return version
    return f"{version} git {described.stdout.strip()}"


class ResultsTable:
    """The folder of one sweep (see the module rules).

    Args:
        folder: the sweep's folder (created when missing).
        plan: the plan's data (:meth:`tools.sweep.plan.SweepPlan.to_dict`).
        version: the code version (:func:`code_version`).

    Raises:
        InputError: the folder holds another plan's results or files of no sweep, or a
            row of ``results.csv`` other than the last is malformed.
    """

    def __init__(self, folder: Path, plan: dict[str, Any], version: str) -> None:
        self.folder = folder
        self.path = folder / RESULTS_NAME
        meta = folder / PLAN_NAME
        if folder.exists() and not folder.is_dir():
            raise InputError(folder, "is not a folder")
        if meta.exists():
            stored = read_json(meta)
            if stored.get("plan") != plan:
                raise InputError(folder, "holds the results of another plan (sweep.json; a "
                                 "plan's files are named from the folder it runs in): "
                                 "choose another --out, or run from that folder")
        elif folder.exists() and any(p.name != MEMORIES_NAME for p in folder.iterdir()):
            raise InputError(folder, "holds files of no sweep: choose a new or empty --out")
        else:
            folder.mkdir(parents=True, exist_ok=True)
            write_text_atomic(meta, json.dumps({"plan": plan, "code_version": version},
                                               indent=2) + "\n")
        self.rows = read_rows(self.path) if self.path.exists() else []
        self._rewrite_if_cut()

    @property
    def done(self) -> set[str]:
        """The ids of the cases with a row."""
        return {str(row["case_id"]) for row in self.rows}

    def append(self, row: dict[str, Any]) -> None:
        """Write ``row`` (keys of :data:`COLUMNS`; others are refused) and sync it."""
        unknown = set(row) - set(COLUMNS)
        if unknown:
            raise ValueError(f"unknown columns {sorted(unknown)}")
        new = not self.path.exists()
        with self.path.open("a", newline="") as f:
            writer = csv.writer(f)
            if new:
                writer.writerow(COLUMNS)
            writer.writerow([_cell(name, row.get(name)) for name in COLUMNS])
            f.flush()
            os.fsync(f.fileno())
        self.rows.append(row)

    def _rewrite_if_cut(self) -> None:
        """Drop a last line cut short, or add the safety columns to a table written before
        them (rule 2), by writing the rows read back."""
        if not self.path.exists():
            return
        text = self.path.read_text()
        buffer = io.StringIO(newline="")
        writer = csv.writer(buffer)
        writer.writerow(COLUMNS)
        for row in self.rows:
            writer.writerow([_cell(name, row.get(name)) for name in COLUMNS])
        if buffer.getvalue() != text:
            write_text_atomic(self.path, buffer.getvalue())


def read_rows(path: Path) -> list[dict[str, Any]]:
    """The rows of a ``results.csv``, cells decoded; a last line cut short is left out.

    Raises:
        InputError: not a results table, or a malformed row before the last.
    """
    try:
        lines = list(csv.reader(io.StringIO(path.read_text(), newline="")))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise InputError(path, f"cannot read a results table: {e}") from None
    header = tuple(lines[0]) if lines else ()
    if header not in (COLUMNS, COLUMNS[:-len(SAFETY_FIGURES)]):
        raise InputError(path, "is not a sweep's results table (its header differs)")
    rows = []
    for number, line in enumerate(lines[1:], start=2):
        try:
            if len(line) != len(header):
                raise ValueError(f"{len(line)} cells, not {len(header)}")
            row = dict.fromkeys(SAFETY_FIGURES)
            row.update({name: _value(name, cell) for name, cell in zip(header, line,
                                                                       strict=True)})
            rows.append(row)
        except ValueError as e:
            if number == len(lines):
                break
            raise InputError(f"{path}:{number}", f"malformed row: {e}") from None
    return rows


def read_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise InputError(path, f"does not read as JSON: {e}") from None
    if not isinstance(data, dict):
        raise InputError(path, "is not a JSON object")
    return data


def _cell(name: str, value: object) -> str:
    if name in TEXT_COLUMNS:
        return "" if value is None else str(value)
    return json.dumps(value)


def _value(name: str, cell: str) -> object:
    if name in TEXT_COLUMNS:
        return cell or None
    return json.loads(cell)
