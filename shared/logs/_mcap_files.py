"""The MCAP adapter: a numbered sequence of files ``<name>-0001.mcap``, ``-0002``, ...

Used by one thread only (the log writer's). Rules:

1. Every OS error (disk full, folder missing or unwritable) is caught here, never
   raised: the current file is abandoned as it is (unfinished but recoverable, see
   :func:`shared.logs.reader.recover`) and messages are counted as lost until a new
   file opens, tried at most every ``retry_period_ns``. The first error of an outage is
   logged; the rest only counted.
2. A file rotates once it reaches ``rotate_size_bytes`` or spans ``rotate_period_ns``
   of log time; a finished file has its summary and index.
3. Numbering continues after the highest number already in the folder, so a restarted
   process never overwrites an earlier run's files.
4. :attr:`McapFiles.size_bytes` is what the files opened here hold on disk so far (the
   finished ones, and the open one up to its last flushed chunk): the writer's quota.
5. Retention: each file opened prunes the folder of old vmnav log files beyond
   ``LogConfig.retain_max_bytes`` and ``retain_max_age_days``, never the new file
   (:mod:`shared.logs.retention`); file times are wall-clock times, so this reads the
   wall clock (``time.time``), not the loop's.
6. Times: callers give the data's time on their clock (``t_ns``); ``log_time`` and
   ``publish_time`` are ``t_ns + unix_offset_ns``, Unix time in ns, so that Foxglove and
   ``mcap info`` show the run's date. Every file opens with the metadata record
   :data:`~shared.logs.topics.CLOCK_METADATA` holding the offset, by which readers get
   the clock's time back (:attr:`shared.logs.reader.LogMessage.clock_ns`). Rotation
   compares clock times.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import re
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import IO, Any

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from shared.config import LogConfig
from shared.logs import topics
from shared.logs.messages import encode_json
from shared.logs.retention import prune_logs
from shared.logs.schemas import Schema

log = logging.getLogger(__name__)

LIBRARY = "vmnav shared.logs (mcap-python)"

_COMPRESSION = {"none": CompressionType.NONE, "lz4": CompressionType.LZ4,
                "zstd": CompressionType.ZSTD}

Record = tuple[str, Schema, Mapping[str, Any]]
"""One message to write: (topic, JSON Schema, message)."""


class McapFiles:
    """Writes records to numbered MCAP files in ``config.output_dir``.

    Args:
        config: folder, chunking, compression, rotation and retry policy.
        name: file name prefix, e.g. ``"robot"``.
        unix_offset_ns: Unix time minus the callers' clock reading, ns, >= 0 (rule 6).
    """

    def __init__(self, config: LogConfig, name: str, unix_offset_ns: int = 0) -> None:
        self._config = config
        self._name = name
        self.unix_offset_ns = unix_offset_ns
        self._dir = Path(config.output_dir)
        self._file: IO[bytes] | None = None
        self._writer: Writer | None = None
        self._schema_ids: dict[str, int] = {}
        self._channel_ids: dict[tuple[str, str], int] = {}
        self._sequence: dict[str, int] = {}
        self._metadata: dict[str, dict[str, str]] = {}
        self._first_t_ns: int | None = None
        self._retry_at_ns: int | None = None
        self._in_outage = False
        self.paths: list[Path] = []
        """Every file opened, in order."""
        self.written = 0
        """Messages handed to the MCAP writer."""
        self.lost = 0
        """Messages not written because of an error."""
        self.errors = 0
        """OS errors met (each abandons a file or a try to open one)."""
        self.last_error: str | None = None
        self._finished_bytes = 0  # files closed or abandoned

    @property
    def size_bytes(self) -> int:
        """Bytes in the files opened here (rule 4)."""
        if self._file is None:
            return self._finished_bytes
        try:
            return self._finished_bytes + self._file.tell()
        except (OSError, ValueError):
            return self._finished_bytes

    def open(self, now_ns: int) -> None:
        """Open the next numbered file unless one is open or a retry is not due yet.

        Args:
            now_ns: the writer thread's wall clock, ns (for the retry period).
        """
        if self._writer is not None or (self._retry_at_ns is not None
                                        and now_ns < self._retry_at_ns):
            return
        path = self._dir / f"{self._name}-{self._next_number():04d}.mcap"
        try:
            self._dir.mkdir(parents=True, exist_ok=True)
            self._file = open(path, "xb")  # noqa: SIM115 - held open across calls, closed in _close
            self._writer = Writer(self._file, chunk_size=self._config.chunk_size_bytes,
                                  compression=_COMPRESSION[self._config.compression])
            self._writer.start(profile="", library=LIBRARY)
            self._writer.add_metadata(topics.CLOCK_METADATA,
                                      {topics.UNIX_OFFSET_KEY: str(self.unix_offset_ns)})
            for name, data in self._metadata.items():
                self._writer.add_metadata(name, data)
        except OSError as e:
            created = self._file is not None
            self._fail(path, e, now_ns)
            if created:  # no empty file per retry while the disk stays full
                with contextlib.suppress(OSError):
                    path.unlink(missing_ok=True)
            return
        self.paths.append(path)
        self._first_t_ns = None
        prune_logs(self._dir, self._config, LIBRARY, time.time(), keep=(path,))
        if self._in_outage:
            log.warning("logging resumed in %s", path)
            self._in_outage = False
        self._retry_at_ns = None

    def write(self, t_ns: int, records: Iterable[Record], now_ns: int) -> None:
        """Write ``records`` with ``log_time = publish_time = t_ns + unix_offset_ns``;
        rotate when due.

        Args:
            t_ns: the data's time on the callers' clock, ns.
            records: the messages (one call's worth, e.g. a MAVLink message and its frame).
            now_ns: the writer thread's wall clock, ns.
        """
        records = list(records)
        if self._writer is not None and self._rotation_due(t_ns):
            self.close(now_ns)
        self.open(now_ns)
        if self._writer is None:
            self.lost += len(records)
            return
        if self._first_t_ns is None:
            self._first_t_ns = t_ns
        done = 0
        unix_ns = t_ns + self.unix_offset_ns
        try:
            for topic, schema, message in records:
                sequence = self._sequence.get(topic, 0) + 1
                self._sequence[topic] = sequence
                self._writer.add_message(self._channel(topic, schema), log_time=unix_ns,
                                         data=encode_json(message), publish_time=unix_ns,
                                         sequence=sequence)
                done += 1
        except OSError as e:
            self.lost += len(records) - done
            self._fail(self.paths[-1], e, now_ns)
        finally:
            self.written += done

    def add_metadata(self, name: str, data: Mapping[str, str], now_ns: int) -> None:
        """Write a metadata record now and into every later file (e.g. ``"run"`` info)."""
        self._metadata[name] = dict(data)
        if self._writer is None:
            self.open(now_ns)  # a new file gets every metadata record
            return
        try:
            self._writer.add_metadata(name, self._metadata[name])
        except OSError as e:
            self._fail(self.paths[-1], e, now_ns)

    def flush(self, now_ns: int) -> None:
        """Close the open chunk, write it and fsync (if configured): a kill loses no more."""
        if self._writer is None or self._file is None:
            return
        try:
            self._writer.flush()
            if self._config.fsync:
                os.fsync(self._file.fileno())
        except OSError as e:
            self._fail(self.paths[-1], e, now_ns)

    def close(self, now_ns: int) -> None:
        """Finish the open file (summary, index, footer) and close it."""
        if self._writer is None or self._file is None:
            return
        try:
            self._writer.finish()
            self._file.flush()
            if self._config.fsync:
                os.fsync(self._file.fileno())
        except OSError as e:
            self._fail(self.paths[-1], e, now_ns)
            return
        self._close()

    def _channel(self, topic: str, schema: Schema) -> int:
        assert self._writer is not None
        title = schema["title"]
        key = (topic, title)
        if key not in self._channel_ids:
            if title not in self._schema_ids:
                self._schema_ids[title] = self._writer.register_schema(
                    name=title, encoding=SchemaEncoding.JSONSchema,
                    data=json.dumps(schema).encode())
            self._channel_ids[key] = self._writer.register_channel(
                topic=topic, message_encoding=MessageEncoding.JSON,
                schema_id=self._schema_ids[title])
        return self._channel_ids[key]

    def _rotation_due(self, t_ns: int) -> bool:
        assert self._file is not None
        return (self._file.tell() >= self._config.rotate_size_bytes
                or (self._first_t_ns is not None
                    and t_ns - self._first_t_ns >= self._config.rotate_period_ns))

    def _next_number(self) -> int:
        pattern = re.compile(rf"{re.escape(self._name)}-(\d+)\.mcap\Z")
        try:
            names = os.listdir(self._dir)
        except OSError:
            names = []
        numbers = [int(m.group(1)) for m in map(pattern.match, names) if m]
        return max(numbers, default=0) + 1

    def _fail(self, path: Path, error: OSError, now_ns: int) -> None:
        self.errors += 1
        self.last_error = f"{path}: {error.strerror or error}"
        if not self._in_outage:
            log.error("log file %s: %s; messages are dropped until a new file opens "
                      "(retrying every %.1f s)", path, error.strerror or error,
                      self._config.retry_period_ns / 1e9)
            self._in_outage = True
        self._retry_at_ns = now_ns + self._config.retry_period_ns
        self._close()

    def _close(self) -> None:
        if self._file is not None:
            self._finished_bytes = self.size_bytes
            with contextlib.suppress(OSError):  # the error that led here was reported
                self._file.close()
        self._file = None
        self._writer = None
        self._schema_ids.clear()
        self._channel_ids.clear()
