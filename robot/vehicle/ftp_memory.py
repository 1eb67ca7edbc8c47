"""The files the robot serves over MAVLink FTP: its visual memory (read-only) and an upload area.

Tree seen by the ground station::

    /memory/          the memory directory, read-only (layout: shared.memory.store)
        manifest.json
        images/<id>.png  features/<id>.npz  thumbnails/<id>.png
    /upload/<name>    writable and flat (the goal photo), at most ``upload_limit_bytes``
                      a file and ``upload_total_bytes`` in all
    /teaching/<id>.png  read-only, from RAM: the thumbnails of the key images of the path
                      being taught (``VehicleTelemetry.teach_thumbnails``); empty otherwise

Rules:

1. A path is split on ``/``; empty parts and ``.`` are dropped. A part starting with
   ``.`` (``..``, and the hidden temporary files of atomic writes) is refused.
2. No symlinks: the real path must be the path built from the parts, so nothing
   outside the two directories can be reached (a swap between the check and the
   ``open`` is not guarded against; the directories belong to the robot).
3. An upload is kept in RAM until TerminateSession commits it; the commit writes
   it with :func:`shared.atomic_file.write_bytes_atomic`, so a reader sees the whole
   file or none. A commit after a failed write, or with bytes never written, keeps
   nothing. A client that gives up mid-way and still terminates the session
   commits the prefix it sent if that prefix has no hole: FTP does not announce
   an upload's length.
4. Refusals are ``OSError``\\ s, which the server turns into NAKs: rules 1 and 2,
   and writes or removals outside ``/upload/``, are PermissionError (FileProtected);
   an upload too large is EFBIG (FailErrno); an upload that would take the upload
   area (its files, other than the one replaced, plus every upload in progress) past
   ``upload_total_bytes`` is ENOSPC (FailErrno), and is then failed for good.
"""

from __future__ import annotations

import errno
import io
import os
import stat
from collections.abc import Callable, Sequence
from pathlib import Path

from shared.atomic_file import write_bytes_atomic
from shared.config import FtpConfig
from shared.errors import InputError
from shared.mavlink.ftp.payload import DirEntry

_AREAS = ("memory", "teaching", "upload")
#: (id, PNG file) of the key images of the path being taught (``/teaching/``).
TeachingFiles = Callable[[], Sequence[tuple[int, bytes]]]


class FileReader:
    """A served file, open for reading (the open descriptor pins the version read).

    Args:
        fd: an open descriptor of a regular file; the reader owns it.
    """

    def __init__(self, fd: int) -> None:
        self._file = io.FileIO(fd, "rb")
        self.size = os.fstat(fd).st_size
        """File length when opened, bytes."""

    def read(self, offset: int, size: int) -> bytes:
        """Up to ``size`` bytes from byte ``offset``."""
        return os.pread(self._file.fileno(), size, offset)

    def close(self) -> None:
        self._file.close()


class BytesReader:
    """A file served from RAM (``/teaching/``): the bytes handed over, which never change."""

    def __init__(self, data: bytes) -> None:
        self._data = data
        self.size = len(data)

    def read(self, offset: int, size: int) -> bytes:
        return self._data[offset:offset + size]

    def close(self) -> None:
        pass


class Upload:
    """A file being uploaded to ``target``: in RAM until :meth:`commit` (rule 3).

    Args:
        target: where the file goes.
        exclusive: refuse at commit time if ``target`` exists by then (CreateFile).
        limit_bytes: the largest file accepted.
        room: the bytes this upload may hold at most under the area's quota (called when
            it grows); None: no quota.
    """

    def __init__(self, target: Path, exclusive: bool, limit_bytes: int,
                 room: Callable[[Upload], int] | None = None) -> None:
        self.target = target
        self.exclusive = exclusive
        self.limit_bytes = limit_bytes
        self._room = room
        self.finished = False
        """Committed or discarded: it holds nothing any more."""
        self._data = bytearray()
        self._written: list[tuple[int, int]] = []  # [start, end) byte ranges, as written
        self._failed: str | None = None

    def write(self, offset: int, data: bytes) -> None:
        """Store ``data`` at byte ``offset``.

        Raises:
            OSError: EFBIG past ``limit_bytes``, ENOSPC past the quota's room (the
                upload is then failed for good).
        """
        end = offset + len(data)
        if end > self.limit_bytes:
            self._failed = f"bytes up to {end} written, limit {self.limit_bytes}"
            raise OSError(errno.EFBIG, f"upload larger than {self.limit_bytes} bytes")
        if end > len(self._data) and self._room is not None and end > self._room(self):
            self._failed = f"bytes up to {end} written, past the upload quota"
            raise OSError(errno.ENOSPC, "upload area quota reached")
        if end > len(self._data):
            self._data.extend(bytes(end - len(self._data)))
        self._data[offset:end] = data
        self._written.append((offset, end))

    def commit(self) -> None:
        """Write the file atomically.

        Raises:
            OSError: EIO after a failed write or for bytes never written;
                FileExistsError (exclusive); EIO if the file cannot be written.
                Nothing is kept then.
        """
        data, written, failed = bytes(self._data), sorted(self._written), self._failed
        self.discard()
        covered = 0
        for start, end in written:
            if start > covered:
                raise OSError(errno.EIO, f"upload has no bytes {covered}..{start - 1}")
            covered = max(covered, end)
        if failed is not None:
            raise OSError(errno.EIO, f"upload failed earlier ({failed})")
        if self.exclusive and os.path.lexists(self.target):
            raise FileExistsError(errno.EEXIST, "file exists", str(self.target))
        try:
            write_bytes_atomic(self.target, data)
        except InputError as e:
            raise OSError(errno.EIO, str(e)) from None

    @property
    def held_bytes(self) -> int:
        """Bytes held in RAM now."""
        return len(self._data)

    def discard(self) -> None:
        self._data, self._written = bytearray(), []
        self.finished = True


class MemoryFileSystem:
    """The :class:`~shared.mavlink.ftp.vehicle.FtpFileSystem` the robot serves (module rules).

    Args:
        memory_dir: the visual memory directory (need not exist yet).
        upload_dir: where uploads land; created if missing.
        upload_limit_bytes: the largest upload accepted, bytes.
        upload_total_bytes: the upload area's quota (files plus uploads in progress), bytes.
        teaching: the files of ``/teaching/`` now (called from the serving thread, so
            it returns an immutable snapshot); None: always empty.
    """

    def __init__(self, memory_dir: str | Path, upload_dir: str | Path,
                 upload_limit_bytes: int = FtpConfig().upload_limit_bytes,
                 upload_total_bytes: int = FtpConfig().upload_total_bytes,
                 teaching: TeachingFiles | None = None) -> None:
        self._teaching = teaching or (lambda: ())
        self.memory_dir = Path(memory_dir)
        self.upload_dir = Path(upload_dir)
        self.upload_limit_bytes = upload_limit_bytes
        self.upload_total_bytes = upload_total_bytes
        self.upload_dir.mkdir(parents=True, exist_ok=True)
        self._uploads: list[Upload] = []  # opened here (the finished pruned at each open)

    def list_directory(self, path: str) -> list[DirEntry]:
        """Entries of ``path`` sorted by name; hidden files and symlinks left out."""
        parts = _parts(path)
        if not parts:
            return [DirEntry(area, True) for area in _AREAS]
        if parts[0] == "teaching":
            if len(parts) > 1:
                raise NotADirectoryError(errno.ENOTDIR, "not a directory", path)
            return sorted((DirEntry(f"{key}.png", False, len(data))
                           for key, data in self._teaching()), key=lambda e: e.name)
        entries = []
        with os.scandir(self._resolve(path, parts)) as it:
            for entry in it:
                if entry.name.startswith(".") or entry.is_symlink():
                    continue
                if entry.is_dir():
                    entries.append(DirEntry(entry.name, True))
                elif entry.is_file():
                    entries.append(DirEntry(entry.name, False, entry.stat().st_size))
        return sorted(entries, key=lambda e: e.name)

    def open_read(self, path: str) -> FileReader | BytesReader:
        """Open a file under ``/memory/``, ``/teaching/`` or ``/upload/``."""
        parts = _parts(path)
        if not parts:
            raise IsADirectoryError(errno.EISDIR, "is a directory", path)
        if parts[0] == "teaching":
            files = {f"{key}.png": data for key, data in self._teaching()}
            if len(parts) != 2 or parts[1] not in files:
                raise FileNotFoundError(errno.ENOENT, "no such file or directory", path)
            return BytesReader(files[parts[1]])
        fd = os.open(self._resolve(path, parts), os.O_RDONLY | os.O_NOFOLLOW)
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise IsADirectoryError(errno.EISDIR, "not a regular file", path)
        return FileReader(fd)

    def open_write(self, path: str, exclusive: bool) -> Upload:
        """Start an upload to ``/upload/<name>``."""
        upload = Upload(self._upload_target(path), exclusive, self.upload_limit_bytes,
                        self._room)
        self._uploads = [u for u in self._uploads if not u.finished]
        self._uploads.append(upload)
        return upload

    def _room(self, upload: Upload) -> int:
        """The bytes ``upload`` may hold under ``upload_total_bytes`` (rule 4): the quota
        less the area's files (but the one it replaces) and the other uploads' bytes."""
        others = sum(u.held_bytes for u in self._uploads if u is not upload)
        with os.scandir(self.upload_dir) as it:
            files = sum(e.stat().st_size for e in it
                        if e.is_file(follow_symlinks=False) and e.path != str(upload.target))
        return self.upload_total_bytes - others - files

    def remove(self, path: str) -> None:
        """Delete ``/upload/<name>``."""
        os.unlink(self._upload_target(path))

    def _upload_target(self, path: str) -> Path:
        parts = _parts(path)
        if len(parts) != 2 or parts[0] != "upload":
            raise PermissionError(errno.EACCES, "writable only as /upload/<name>", path)
        return self._resolve(path, parts)

    def _resolve(self, path: str, parts: list[str]) -> Path:
        """The local path of ``parts`` (rule 2)."""
        roots = {"memory": self.memory_dir, "upload": self.upload_dir}
        if parts[0] not in roots:
            raise FileNotFoundError(errno.ENOENT, "no such file or directory", path)
        root = roots[parts[0]]
        local = root.joinpath(*parts[1:])
        if os.path.realpath(local) != os.path.join(os.path.realpath(root), *parts[1:]):
            raise PermissionError(errno.EACCES, "symlinks are not served", path)
        return local


def _parts(path: str) -> list[str]:
    """``path`` split on ``/`` (rule 1).

    Raises:
        PermissionError: a part starts with ``.`` or holds a NUL or backslash.
    """
    parts = [p for p in path.split("/") if p not in ("", ".")]
    if any(p.startswith(".") or "\0" in p or "\\" in p for p in parts):
        raise PermissionError(errno.EACCES, "path refused", path)
    return parts
