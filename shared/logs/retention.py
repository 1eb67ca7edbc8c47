"""Retention of a log folder: the oldest of vmnav's own log files go once the folder holds
more than ``LogConfig.retain_max_bytes`` of them, or once they are older than
``LogConfig.retain_max_age_days``.

Applied by the log writer's thread whenever it opens a file
(:class:`shared.logs._mcap_files.McapFiles`: the robot's and the ground station's MCAP
files, at start and at each rotation), so the control loop never waits for it. Rules:

1. Only vmnav's own files are candidates, in the folder itself (not below it): numbered
   MCAP files ``<name>-NNNN.mcap`` whose header names vmnav's writer
   (:data:`shared.logs._mcap_files.LIBRARY`), and the ground station's tlogs
   ``ground-YYYYmmdd-HHMMSS[-N].tlog``. Anything else (a recovered copy, another tool's
   log, a note) is never touched.
2. A file being written is never removed: the files given as ``keep``, and any file
   modified in the last :data:`ACTIVE_S` seconds, which may be another process's open
   log (writers flush at least every second while they have data).
3. Age first: every candidate last modified more than ``retain_max_age_days`` ago goes.
   Then size: while the candidates (the kept and active ones included) hold more than
   ``retain_max_bytes``, the oldest removable one (by modification time, then name)
   goes. A limit of 0 is no limit.
4. Errors (a file vanished, no permission) are counted and logged, never raised: a
   retention problem must not stop the robot or its log.
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path

from shared.config import LogConfig

log = logging.getLogger(__name__)

ACTIVE_S = 60
"""A file modified less than this long ago may be open in another writer (rule 2), s."""
SECONDS_PER_DAY = 86_400

_MCAP = re.compile(r".+-\d{4,}\.mcap\Z")
_TLOG = re.compile(r"ground-\d{8}-\d{6}(-\d+)?\.tlog\Z")
_MAGIC = b"\x89MCAP0\r\n"
_HEADER_BYTES = 512  # magic, opcode, length, profile and library strings


@dataclass(frozen=True, slots=True)
class Pruned:
    """What :func:`prune_logs` did.

    Attributes:
        removed: the files deleted, oldest first.
        freed_bytes: their size.
        errors: files that could not be examined or deleted.
    """

    removed: tuple[Path, ...]
    freed_bytes: int
    errors: int


def is_vmnav_log(path: Path, library: str) -> bool:
    """Whether ``path``'s name is one of vmnav's log patterns (rule 1) and, for MCAP, its
    header names ``library``. Reads at most the file's first 512 bytes.

    Raises:
        OSError: the file cannot be read.
    """
    if _TLOG.match(path.name):
        return True
    if not _MCAP.match(path.name):
        return False
    with open(path, "rb") as f:
        head = f.read(_HEADER_BYTES)
    return head.startswith(_MAGIC) and _header_library(head[len(_MAGIC):]) == library


def _header_library(record: bytes) -> str | None:
    """The library string of an MCAP Header record (opcode 0x01, u64 record length, then
    two strings, each a u32 byte count and UTF-8: profile, library); None if it is not one
    or does not fit in ``record``."""
    if len(record) < 13 or record[0] != 0x01:
        return None
    profile_end = 13 + int.from_bytes(record[9:13], "little")
    library_start = profile_end + 4
    if len(record) < library_start:
        return None
    library_end = library_start + int.from_bytes(record[profile_end:library_start], "little")
    if len(record) < library_end:
        return None
    return record[library_start:library_end].decode("utf-8", "replace")


def prune_logs(folder: Path, config: LogConfig, library: str, now_s: float,
               keep: Collection[Path] = ()) -> Pruned:
    """Delete the oldest of vmnav's log files in ``folder`` beyond the limits (module rules).

    Args:
        folder: the log folder.
        config: ``retain_max_bytes`` and ``retain_max_age_days``.
        library: the MCAP header's library that marks vmnav's files.
        now_s: the wall clock, Unix s (file times are compared with it).
        keep: files never to delete (the ones being written).
    """
    kept = {Path(p).resolve() for p in keep}
    errors = 0
    candidates: list[tuple[float, str, int, Path, bool]] = []  # mtime, name, size, path, removable
    try:
        entries = list(os.scandir(folder))
    except OSError as e:
        log.warning("log retention: cannot list %s: %s", folder, e.strerror or e)
        return Pruned((), 0, 1)
    for entry in entries:
        path = Path(entry.path)
        try:
            if not entry.is_file(follow_symlinks=False) or not is_vmnav_log(path, library):
                continue
            stat = entry.stat(follow_symlinks=False)
        except OSError:
            errors += 1
            continue
        removable = path.resolve() not in kept and now_s - stat.st_mtime >= ACTIVE_S
        candidates.append((stat.st_mtime, entry.name, stat.st_size, path, removable))
    candidates.sort()
    max_age_s = config.retain_max_age_days * SECONDS_PER_DAY
    total = sum(c[2] for c in candidates)
    removed: list[Path] = []
    freed = 0
    for mtime, _, size, path, removable in candidates:
        too_old = max_age_s > 0 and now_s - mtime > max_age_s
        too_big = 0 < config.retain_max_bytes < total
        if not removable or not (too_old or too_big):
            continue
        try:
            path.unlink()
        except FileNotFoundError:
            pass  # someone else removed it: it no longer counts either way
        except OSError as e:
            errors += 1
            log.warning("log retention: cannot delete %s: %s", path, e.strerror or e)
            continue
        removed.append(path)
        freed += size
        total -= size
    if removed:
        log.info("log retention: deleted %d old log file(s) in %s (%.1f MB)", len(removed),
                 folder, freed / 1e6)
    return Pruned(tuple(removed), freed, errors)
