"""Atomic file writes: a temporary file in the same folder, flushed, then ``os.replace``.

A reader sees the old file or the new one, never a half-written one; a failed
write leaves the old file untouched.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from shared.errors import InputError


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` atomically.

    Raises:
        InputError: the folder does not exist or cannot be written (names the path).
    """
    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as e:
        raise InputError(path, f"cannot write: {e.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _mode_for(path))
        os.replace(tmp, path)
    except OSError as e:
        os.unlink(tmp)
        raise InputError(path, f"cannot write: {e.strerror}") from None
    except BaseException:
        os.unlink(tmp)
        raise


def _mode_for(path: Path) -> int:
    """The replaced file's permissions, or rw-r--r-- for a new file (mkstemp's are 0600)."""
    try:
        return path.stat().st_mode & 0o777
    except FileNotFoundError:
        return 0o644


def write_text_atomic(path: str | Path, text: str) -> None:
    """Replace ``path`` with UTF-8 ``text`` atomically (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))
