"""Walking an MCAP file that may be finished, unfinished, truncated or damaged.

A killed writer leaves the header, the chunks it closed and maybe part of the next
one, with no summary (mcap-logging.md §1 "Crash behaviour"). :class:`RecordScan`
reads records in order until the data section ends (DataEnd) or the bytes stop
making sense, and says where and why it stopped. A chunk whose bytes fail to
decompress or to match their CRC is skipped and counted: its length is intact, so
the next record can still be read (as ``mcap recover`` does); so is a chunk declaring
more than ``_chunks.MAX_CHUNK_BYTES`` uncompressed, or more than the file's inflation
budget has left (never inflated). A top-level record
cut short or with an impossible length ends the scan: nothing after it has a
known start.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import zstandard
from mcap.exceptions import EndOfFile, McapError, RecordLengthLimitExceeded
from mcap.records import Chunk, DataEnd, McapRecord
from mcap.stream_reader import StreamReader

from shared.errors import InputError
from shared.logs._chunks import ClampedFile, open_chunk

MAGIC = b"\x89MCAP0\r\n"
"""The 8 bytes an MCAP file starts and ends with."""

READ_ERRORS = (McapError, ValueError, RuntimeError, struct.error, zstandard.ZstdError, OSError,
               OverflowError)
"""What the mcap readers and their decompressors (lz4: RuntimeError, zstandard:
ZstdError) raise on bad bytes; CRCValidationError is a ValueError; a length of 2^63 or
more inside a chunk gives OverflowError (reading past a chunk's end does not allocate)."""


def check_magic(f: IO[bytes], path: Path) -> int:
    """Check that ``f`` starts like an MCAP file; returns its size, bytes; leaves it at 0.

    Raises:
        InputError: naming ``path``, if the file is too short or starts otherwise.
    """
    size = f.seek(0, 2)
    f.seek(0)
    start = f.read(len(MAGIC))
    f.seek(0)
    if start != MAGIC:
        what = "is empty" if size == 0 else f"starts with {start[:4].hex(' ')}"
        raise InputError(path, f"not an MCAP file ({size} bytes; {what}, "
                               f"MCAP files start with {MAGIC[:4].hex(' ')} 'MCAP0')")
    return size


class RecordScan:
    """The data-section records of an MCAP file, read in order, with chunks opened.

    After :meth:`records` is exhausted: :attr:`complete` tells whether the data
    section ended properly (DataEnd), :attr:`problem` why not (one line),
    :attr:`skipped_chunks` how many chunks were damaged.

    Args:
        f: the file, binary, seekable, at offset 0, reads clamped to its size.
        size_bytes: its size (no record can be longer).
    """

    def __init__(self, f: ClampedFile, size_bytes: int) -> None:
        self._f = f
        self._size = size_bytes
        self.complete = False
        self.problem: str | None = None
        self.skipped_chunks = 0
        self.end_offset = len(MAGIC)
        """The byte after the last whole record read, i.e. what was usable."""

    def records(self) -> Iterator[McapRecord]:
        """Header, Schema, Channel, Message, Metadata, Attachment... up to DataEnd."""
        records = StreamReader(self._f, emit_chunks=True, record_size_limit=self._size).records
        while True:
            try:
                record = next(records)
            except StopIteration:
                return
            except READ_ERRORS as e:
                self.problem = self._describe(e)
                return
            self.end_offset = self._f.tell()
            if isinstance(record, DataEnd):
                self.complete = True
                return
            if isinstance(record, Chunk):
                try:
                    inner = open_chunk(record, self._f.inflation)
                except READ_ERRORS:
                    self.skipped_chunks += 1
                    continue
                yield from inner
            else:
                yield record

    def _describe(self, error: Exception) -> str:
        at, size = self.end_offset, self._size
        if isinstance(error, EndOfFile) and at == size:
            return (f"unfinished: no summary or footer after byte {at} "
                    "(the writer was killed or never closed the file)")
        if isinstance(error, EndOfFile | RecordLengthLimitExceeded):
            return (f"truncated: the record at byte {at} runs past the end of the file "
                    f"({size} bytes)")
        return f"corrupt record at byte {at} of {size}: {error}"
