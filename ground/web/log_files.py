"""The ground logs the page lists and downloads: ``--log DIR``'s ``ground-NNNN.mcap`` and
``ground-<stamp>.tlog`` (``ground.ground_log``), and nothing else.

Rules:

1. Only a name of the ground log's own form (:data:`LOG_NAME`) is served, from ``DIR``
   itself, and only a regular file that is not a symlink (checked on the open file): no
   other path of the machine, however the name is spelled (``..``, ``/``, ``%2f``).
2. A file is served up to the size it had when opened: the log being written grows
   meanwhile, and the answer keeps the ``Content-Length`` it announced. The MCAP being
   written has no summary yet (MCAP readers read it to where it ends).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from shared.errors import InputError

#: The names of the ground log's files (``ground.ground_log``).
LOG_NAME = re.compile(r"ground-[0-9]{4,}\.mcap|ground-[0-9]{8}-[0-9]{6}(-[0-9]+)?\.tlog")
#: Bytes read at a time while serving a file.
CHUNK_BYTES = 1 << 16


@dataclass(frozen=True, slots=True)
class LogFile:
    """One log file.

    Attributes:
        name: its name in the log folder.
        size_bytes: its length when listed.
        modified_unix_s: when it was last written, s since 1970-01-01 UTC.
    """

    name: str
    size_bytes: int
    modified_unix_s: float


def list_logs(log_dir: Path) -> list[LogFile]:
    """The ground log files in ``log_dir`` (rule 1), newest first; none if it is missing."""
    found = []
    try:
        with os.scandir(log_dir) as entries:
            for entry in entries:
                if LOG_NAME.fullmatch(entry.name) and entry.is_file(follow_symlinks=False):
                    info = entry.stat(follow_symlinks=False)
                    found.append(LogFile(entry.name, info.st_size, info.st_mtime))
    except FileNotFoundError:
        return []
    return sorted(found, key=lambda f: (-f.modified_unix_s, f.name))


def open_log(log_dir: Path, name: str) -> tuple[int, Iterator[bytes]]:
    """Open the log file ``name`` of ``log_dir`` (rules 1, 2).

    Returns:
        Its size now, and its bytes up to that size in chunks (the iterator closes the file
        when exhausted or closed).

    Raises:
        InputError: not a ground log's name, or no such log file.
    """
    if not LOG_NAME.fullmatch(name):
        raise InputError("log", f"{name!r:.60} is not a ground log's name (ground-NNNN.mcap, "
                                "ground-<stamp>.tlog)")
    try:
        fd = os.open(log_dir / name, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError as e:
        raise InputError("log", f"{name}: {e.strerror}") from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise InputError("log", f"{name}: not a regular file")
    return info.st_size, _chunks(fd, info.st_size)


def _chunks(fd: int, size: int) -> Iterator[bytes]:
    try:
        offset = 0
        while offset < size:
            data = os.pread(fd, min(CHUNK_BYTES, size - offset), offset)
            if not data:  # truncated meanwhile: the client sees a short answer
                return
            offset += len(data)
            yield data
    finally:
        os.close(fd)
