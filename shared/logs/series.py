"""The files of one log in time order: one file, several, or a rotated series from its first.

A :class:`~shared.logs.writer.LogWriter` rotates into numbered files ``<name>-0001.mcap``,
``-0002``, ...; the numbering carries on after the files already in the folder, so
one run's files have consecutive numbers and the next run's follow them. A writer
that marks its run (the robot's field log, :class:`robot.field_log.FieldLog`) puts a
unique id under :data:`SERIES_KEY` in its :data:`RUN_METADATA` metadata, which every
file of the run repeats.

Rules of :func:`log_series`:

1. One file numbered ``-NNNN`` whose run metadata names its series stands for the
   series from it on: it and the files numbered after it in its folder, as long as
   each exists and names the same series. Any other single file is just itself.
2. Several files are taken as given (each once) and put in order: by number when they
   are all numbered files of one name in one folder, else by their first message's time.
3. Bad input is an :class:`~shared.errors.InputError` naming the files: a file that is
   not a finished MCAP file (unfinished ones name ``vmnav log recover``), files of
   different series, a file whose first message is older than the last message of the
   file before it (an overlap; by up to :data:`OVERLAP_SLACK_NS` is no overlap when the
   file is the next number of the same name), or a gap (files of one name in one folder
   whose numbers skip one: the missing file is named).

The slack: a writer's threads log a little out of time order (a SIP received while a
cycle was being logged), so a rotation may put a message slightly older than the
previous file's last into the next file.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from shared.errors import InputError
from shared.logs.reader import RECOVER_HINT, log_info, read_metadata

RUN_METADATA = "run"
"""Name of the metadata record that describes the run."""
SERIES_KEY = "series"
"""Key of :data:`RUN_METADATA` holding the run's unique series id."""
OVERLAP_SLACK_NS = 1_000_000_000
"""How much older than the previous file's last message the first message of the next
file of a rotation may be, ns."""

_NUMBERED = re.compile(r"(?P<name>.+)-(?P<number>\d{4,})\.mcap\Z")


@dataclass(frozen=True, slots=True)
class _Part:
    """A file; ``name`` is its folder and name prefix when numbered (``.../robot``)."""

    path: Path
    series: str | None
    start_ns: int | None
    end_ns: int | None
    name: str | None
    number: int | None


def log_series(paths: Sequence[str | Path]) -> tuple[Path, ...]:
    """The files of one log, in time order (see the module docstring).

    Args:
        paths: one file (standing for its series from it on) or several.

    Raises:
        InputError: no file, a file missing or not a finished MCAP file, files of
            different series, overlapping times, or a gap in the numbering.
    """
    if not paths:
        raise InputError("log", "no file given")
    parts = [_part(Path(p)) for p in paths]
    if len(parts) == 1:
        parts = _rest_of_series(parts[0])
    seen: dict[Path, Path] = {}
    for part in parts:
        key = part.path.resolve()
        if key in seen:
            raise InputError(part.path, f"is given twice (also as {seen[key]})")
        seen[key] = part.path
    a = parts[0]
    for b in parts[1:]:
        if b.series != a.series:
            raise InputError(b.path, f"is not of the same run as {a.path} (series "
                                     f"{b.series or 'none'} and {a.series or 'none'})")
    _check_numbering(parts)
    names = {p.name for p in parts}
    if None in names or len(names) > 1:
        parts.sort(key=lambda p: (p.start_ns is None, p.start_ns or 0))
    else:
        parts.sort(key=lambda p: p.number or 0)
    timed = [p for p in parts if p.start_ns is not None]
    for before, after in itertools.pairwise(timed):
        assert before.end_ns is not None and after.start_ns is not None
        rotated = (before.name is not None and after.name == before.name
                   and after.number == (before.number or 0) + 1)
        if after.start_ns < before.end_ns - (OVERLAP_SLACK_NS if rotated else 0):
            raise InputError(after.path, f"overlaps {before.path}: it starts at "
                                         f"{after.start_ns / 1e9:.3f} s, before {before.path.name} "
                                         f"ends at {before.end_ns / 1e9:.3f} s")
    return tuple(p.path for p in parts)


def series_name(files: Sequence[Path]) -> str:
    """How messages name a log: its file, or its first file and how many more follow."""
    return str(files[0]) if len(files) == 1 else f"{files[0]} (+{len(files) - 1} files)"


def _part(path: Path) -> _Part:
    info = log_info(path)
    if not info.complete:
        raise InputError(path, f"{info.problem}; " + RECOVER_HINT.format(path=path))
    series = (read_metadata(path).get(RUN_METADATA, {}).get(SERIES_KEY)
              if RUN_METADATA in info.metadata else None)
    match = _NUMBERED.match(path.name)
    return _Part(path, series, info.start_ns, info.end_ns,
                 str(path.parent.resolve() / match["name"]) if match else None,
                 int(match["number"]) if match else None)


def _rest_of_series(first: _Part) -> list[_Part]:
    if first.series is None or first.number is None:
        return [first]
    parts, number = [first], first.number
    while True:
        number += 1
        path = first.path.with_name(f"{Path(str(first.name)).name}-{number:04d}.mcap")
        if not path.exists():
            return parts
        part = _part(path)
        if part.series != first.series:
            return parts
        parts.append(part)


def _check_numbering(parts: list[_Part]) -> None:
    by_name: dict[str, list[_Part]] = {}
    for part in parts:
        if part.name is not None:
            by_name.setdefault(part.name, []).append(part)
    for name, numbered in by_name.items():
        numbered.sort(key=lambda p: p.number or 0)
        for before, after in itertools.pairwise(numbered):
            assert before.number is not None and after.number is not None
            if after.number != before.number + 1:
                missing = before.path.with_name(f"{Path(name).name}-{before.number + 1:04d}.mcap")
                raise InputError(missing, f"missing from the series: a gap between "
                                          f"{before.path.name} and {after.path.name}")
