"""Reading MCAP records and chunks with every length checked before it is allocated.

mcap 1.x trusts the file: ``f.read(n)`` of a declared length allocates ``n`` bytes
(2^63 gives OverflowError), ``zstandard.decompress(data, uncompressed_size)`` allocates
the size a chunk declares, ``lz4.frame.decompress`` inflates whatever the frame holds,
and ``SeekingReader.iter_messages`` looks channels up in the summary unchecked (a
damaged summary gives KeyError). Here:

* :class:`ClampedFile` gives the mcap readers a file whose ``read(n)`` never asks for
  more than what is left in it;
* :func:`open_chunk` decompresses a chunk only if it declares at most
  :data:`MAX_CHUNK_BYTES`, and stops inflating one byte past what it declares;
* :func:`messages_in_time_order` reads a finished file's messages through its summary,
  as ``SeekingReader.iter_messages`` does (same order), once :func:`check_summary` found
  the summary consistent.

Every problem raises :class:`mcap.exceptions.McapError` (a :class:`DamagedLogError`), so
that the callers' handling of damaged files covers it.
"""

from __future__ import annotations

import dataclasses
import heapq
import io
import itertools
from collections.abc import Collection, Iterator
from typing import IO

import lz4.frame
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, ChunkIndex, McapRecord, Message, Schema
from mcap.stream_reader import breakup_chunk
from mcap.summary import Summary

MAX_CHUNK_BYTES = 64 * 2**20
"""The most a chunk may hold uncompressed, bytes. vmnav's writer closes a chunk at
``[log] chunk_size_bytes`` (1 MiB by default) plus at most one message."""
MAX_QUEUED_BYTES = 2 * MAX_CHUNK_BYTES
"""The most message data :func:`messages_in_time_order` holds at once, bytes: the
messages of chunks overlapping in log time wait in its queue. vmnav's writer logs in
time order, so its chunks barely overlap."""


MAX_INFLATION = 100
"""The chunks of a file may inflate to at most this many times its size together (or one
chunk's limit, if more): JSON logs compress about 10:1, JPEG frames not at all, while
each 4 kB zstd frame of a crafted file can inflate to 64 MiB."""


class DamagedLogError(McapError):
    """A record or chunk whose declared sizes or references cannot be right."""


class InflationBudget:
    """What the chunks of one file may still inflate to, bytes (:data:`MAX_INFLATION`).

    Args:
        size_bytes: the file's size.
    """

    def __init__(self, size_bytes: int) -> None:
        self.left_bytes = max(MAX_CHUNK_BYTES, MAX_INFLATION * size_bytes)

    def take(self, n_bytes: int) -> None:
        """Count ``n_bytes`` about to be inflated.

        Raises:
            DamagedLogError: the budget would be exceeded (nothing is counted then).
        """
        if n_bytes > self.left_bytes:
            raise DamagedLogError(f"its chunks inflate to more than {MAX_INFLATION} times the "
                                  "file's size")
        self.left_bytes -= n_bytes


class ClampedFile(io.BufferedIOBase):
    """A binary file of known size whose ``read(n)`` reads at most what is left.

    Args:
        f: the file, binary and seekable.
        size_bytes: its size.
    """

    def __init__(self, f: IO[bytes], size_bytes: int) -> None:
        super().__init__()
        self._f = f
        self._size = size_bytes
        self.inflation = InflationBudget(size_bytes)
        """What the file's chunks may still inflate to, shared by its readers."""

    def read(self, size: int | None = -1, /) -> bytes:
        """Up to ``size`` bytes (all that is left if negative or None)."""
        left = max(0, self._size - self._f.tell())
        return self._f.read(left if size is None or size < 0 else min(size, left))

    def seek(self, offset: int, whence: int = io.SEEK_SET, /) -> int:
        """As :meth:`io.IOBase.seek`."""
        return self._f.seek(offset, whence)

    def tell(self) -> int:
        """As :meth:`io.IOBase.tell`."""
        return self._f.tell()

    def readable(self) -> bool:
        """True."""
        return True

    def seekable(self) -> bool:
        """True."""
        return True


def open_chunk(chunk: Chunk, budget: InflationBudget) -> list[McapRecord]:
    """The records of ``chunk`` (Schema, Channel, Message), its CRC checked.

    Args:
        chunk: the chunk.
        budget: its file's; what it declares is taken from it before inflating.

    Raises:
        DamagedLogError: it declares more than :data:`MAX_CHUNK_BYTES` or than is left
            in ``budget``, or inflates to another size than it declares.
        McapError, ValueError, RuntimeError, zstandard.ZstdError, OverflowError, struct.error:
            the bytes are damaged otherwise (as mcap's ``breakup_chunk``).
    """
    declared = chunk.uncompressed_size
    if declared > MAX_CHUNK_BYTES:
        raise DamagedLogError(f"a chunk declares {declared} bytes uncompressed, more than the "
                              f"{MAX_CHUNK_BYTES} allowed")
    budget.take(declared)
    if chunk.compression == "zstd":
        data = _inflate_zstd(chunk.data, declared + 1)
    elif chunk.compression == "lz4":
        data = _inflate_lz4(chunk.data, declared + 1)
    elif chunk.compression == "":
        data = chunk.data
    else:
        raise DamagedLogError(f"a chunk uses compression {chunk.compression[:20]!r} "
                              "(only zstd, lz4 or none)")
    if len(data) != declared:
        raise DamagedLogError(f"a chunk declares {declared} bytes uncompressed but "
                              f"{'holds more' if len(data) > declared else f'holds {len(data)}'}")
    return breakup_chunk(dataclasses.replace(chunk, compression="", data=data),
                         validate_crc=True)


def _inflate_zstd(data: bytes, limit: int) -> bytes:
    """At most ``limit`` bytes of the zstd frame ``data``, whatever size it declares."""
    decompressor = zstandard.ZstdDecompressor(max_window_size=MAX_CHUNK_BYTES)
    if zstandard.frame_content_size(data) in range(limit):
        # one allocation of the size the frame declares; zstd fails if it inflates to more
        return decompressor.decompress(data)
    out = bytearray()
    with decompressor.stream_reader(data) as reader:
        while len(out) < limit:
            piece = reader.read(limit - len(out))
            if not piece:
                break
            out += piece
    return bytes(out)


def _inflate_lz4(data: bytes, limit: int) -> bytes:
    """At most ``limit`` bytes of the lz4 frame ``data``."""
    decompressor = lz4.frame.LZ4FrameDecompressor()
    out: bytes = decompressor.decompress(data, max_length=limit)
    if len(out) < limit and not decompressor.eof:
        raise DamagedLogError("a chunk's lz4 frame ends before its end mark")
    return out


def check_summary(summary: Summary, size_bytes: int) -> None:
    """Check that the summary of a file of ``size_bytes`` refers only to what it holds.

    Raises:
        DamagedLogError: a channel's schema, a chunk's channel or a chunk's place is
            missing or outside the file.
    """
    for channel in summary.channels.values():
        if channel.schema_id != 0 and channel.schema_id not in summary.schemas:
            raise DamagedLogError(f"the summary's channel {channel.id} refers to schema "
                                  f"{channel.schema_id}, which it does not hold")
    for index in summary.chunk_indexes:
        if index.chunk_start_offset + index.chunk_length > size_bytes:
            raise DamagedLogError(f"the summary places a chunk at byte "
                                  f"{index.chunk_start_offset}, past the end of the file")
        unknown = set(index.message_index_offsets) - set(summary.channels)
        if unknown:
            raise DamagedLogError(f"the summary's chunk at byte {index.chunk_start_offset} "
                                  f"holds channel {min(unknown)}, which it does not list")
    if summary.statistics is not None:
        unknown = set(summary.statistics.channel_message_counts) - set(summary.channels)
        if unknown:
            raise DamagedLogError(f"the summary counts messages of channel {min(unknown)}, "
                                  "which it does not list")


def messages_in_time_order(
    f: ClampedFile, summary: Summary, topics: Collection[str] | None
) -> Iterator[tuple[Schema | None, Channel, Message]]:
    """The messages of the chunks ``summary`` indexes, by log time (ties: file order).

    Chunks are read when the earliest message queued is not before their first
    message, so only the chunks overlapping in time are held at once; the data of the
    messages queued plus the next chunk's declared size may reach at most
    :data:`MAX_QUEUED_BYTES` (many small zstd chunks, each declaring 64 MiB at the same
    time, would otherwise all be held).

    Args:
        f: the file.
        summary: its summary, checked by :func:`check_summary`.
        topics: only these topics (all when None).

    Raises:
        DamagedLogError: a chunk is not where the summary says, too large, or chunks
            overlapping in time hold too much.
    """
    wanted = None if topics is None else {
        channel.id for channel in summary.channels.values() if channel.topic in topics}
    tiebreak = itertools.count()
    queue: list[tuple[int, int, int, int, ChunkIndex | Message]] = [
        (index.message_start_time, index.chunk_start_offset, -1, next(tiebreak), index)
        for index in summary.chunk_indexes
        if wanted is None or not index.message_index_offsets
        or not wanted.isdisjoint(index.message_index_offsets)]
    heapq.heapify(queue)
    queued_bytes = 0
    while queue:
        _, offset, _, _, item = heapq.heappop(queue)
        if isinstance(item, Message):
            queued_bytes -= len(item.data)
            channel = summary.channels[item.channel_id]
            yield summary.schemas.get(channel.schema_id), channel, item
            continue
        # a chunk declaring more than MAX_CHUNK_BYTES is refused as such by open_chunk
        next_bytes = min(item.uncompressed_size, MAX_CHUNK_BYTES)
        if queued_bytes + next_bytes > MAX_QUEUED_BYTES:
            raise _overlap_error(offset, queued_bytes + next_bytes)
        for position, record in enumerate(_read_chunk(f, offset)):
            if not isinstance(record, Message) or (wanted is not None
                                                   and record.channel_id not in wanted):
                continue
            if record.channel_id not in summary.channels:
                raise DamagedLogError(f"the chunk at byte {offset} holds a message on channel "
                                      f"{record.channel_id}, which the summary does not list")
            heapq.heappush(queue, (record.log_time, offset, position, next(tiebreak), record))
            queued_bytes += len(record.data)
        if queued_bytes > MAX_QUEUED_BYTES:
            raise _overlap_error(offset, queued_bytes)


def _overlap_error(offset: int, queued_bytes: int) -> DamagedLogError:
    return DamagedLogError(f"chunks overlapping in log time up to the one at byte {offset} "
                           f"hold {queued_bytes} bytes at once, more than the "
                           f"{MAX_QUEUED_BYTES} allowed")


def _read_chunk(f: ClampedFile, offset: int) -> list[McapRecord]:
    f.seek(offset)
    stream = ReadDataStream(f)
    if stream.read1() != Opcode.CHUNK:
        raise DamagedLogError(f"the summary places a chunk at byte {offset}, where there is "
                              "another record")
    stream.read8()  # the record's length: Chunk.read reads its fields, each clamped by f
    return open_chunk(Chunk.read(stream), f.inflation)
