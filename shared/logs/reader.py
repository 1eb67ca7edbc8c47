"""Reading field logs: a summary of any MCAP file, its messages, and recovery after a crash.

* :func:`log_info`: topics, counts, schema names, duration and rates; from the
  summary of a finished file, by scanning an unfinished or damaged one.
* :func:`read_messages`: the decoded JSON messages of a finished file, in log time order,
  each with its time on the writer's clock (:attr:`LogMessage.clock_ns`);
  :func:`read_metadata`: its metadata records.
* :func:`recover`: rewrite an unfinished, truncated or damaged file into a valid,
  indexed one, keeping every message of every intact chunk; the source is only read.

Times: a log's ``log_time`` is Unix time, ns; its metadata record
:data:`~shared.logs.topics.CLOCK_METADATA` holds the offset from the writer's clock (time
since boot, or simulated time), which readers subtract to get that clock back. Logs
written before the record existed have their clock's time in ``log_time``: offset 0.

Bad files raise :class:`~shared.errors.InputError` with one line naming the file. Crafted
ones cannot make a reader allocate more than the file's size plus one chunk of at most
64 MiB (:mod:`._chunks`): reads are clamped to the file, a chunk is inflated only up to
what it declares, the summary is checked before use, and messages are parsed by
:func:`shared.json_file.parse_json` (nesting and number limits).
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections import Counter
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import IO, Any

from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Header, Message, Metadata, Schema, Statistics
from mcap.summary import Summary
from mcap.well_known import MessageEncoding
from mcap.writer import CompressionType, Writer

from shared.errors import InputError
from shared.json_file import parse_json
from shared.logs import topics as _topics
from shared.logs._chunks import ClampedFile, check_summary, messages_in_time_order
from shared.logs._scan import MAGIC, READ_ERRORS, RecordScan, check_magic

RECOVER_HINT = "`vmnav log recover {path}` rewrites what it holds into a valid file"
MESSAGE_INT_BITS = 128
"""A message's integers lie in [-2^128, 2^128): a random generator's state (PCG64: two
128-bit integers) is logged with each mission."""


@dataclass(frozen=True, slots=True)
class TopicInfo:
    """One topic of a log.

    Attributes:
        topic: e.g. ``/servo/state``.
        schema_name: e.g. ``foxglove.CompressedImage`` ("" without a schema).
        message_encoding: e.g. ``json``.
        message_count: messages on the topic.
        rate_hz: messages per second of the log's duration (0 for a log shorter than 1 ns).
    """

    topic: str
    schema_name: str
    message_encoding: str
    message_count: int
    rate_hz: float


@dataclass(frozen=True, slots=True)
class LogInfo:
    """What an MCAP file holds.

    Attributes:
        path: the file.
        size_bytes: its size.
        library: the writer named in the header.
        complete: the file is finished (summary and index); False for a killed writer's file.
        problem: why it is not complete, one line (None when complete).
        message_count: messages read (all of them when complete).
        start_ns, end_ns: first and last ``log_time``, ns (None without messages): Unix
            time when ``unix_offset_ns`` is recorded.
        topics: per topic, sorted by name.
        metadata: names of the metadata records (e.g. ``clock``, ``run``).
        unix_offset_ns: Unix time minus the writer's clock, ns, as recorded in the file;
            None for a log written before it was recorded (its times are the clock's).
    """

    path: Path
    size_bytes: int
    library: str
    complete: bool
    problem: str | None
    message_count: int
    start_ns: int | None
    end_ns: int | None
    topics: tuple[TopicInfo, ...]
    metadata: tuple[str, ...]
    unix_offset_ns: int | None = None

    @property
    def duration_s(self) -> float:
        """Time from the first to the last message, s."""
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / 1e9

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the fields plus ``duration_s``; the path as a string."""
        data = asdict(self)
        data["path"] = str(self.path)
        data["duration_s"] = self.duration_s
        return data


@dataclass(frozen=True, slots=True)
class LogMessage:
    """One decoded message.

    Attributes:
        topic, schema_name: where it was logged and its schema.
        log_time_ns, publish_time_ns: its MCAP times, ns (Unix time in logs that record
            their clock's offset).
        sequence: per-topic counter from the writer (1, 2, ...).
        data: the decoded JSON object.
        clock_ns: its time on the writer's clock, ns: ``log_time_ns`` minus the file's
            recorded offset (time since boot, or simulated time; what control, replay and
            teach drives use).
    """

    topic: str
    schema_name: str
    log_time_ns: int
    publish_time_ns: int
    sequence: int
    data: dict[str, Any]
    clock_ns: int


@dataclass(frozen=True, slots=True)
class RecoverReport:
    """What :func:`recover` kept.

    Attributes:
        src, dst: the damaged file and the valid one written.
        messages: messages copied.
        topics: channels copied.
        metadata, attachments: records copied.
        skipped_chunks: damaged chunks left out.
        orphaned: messages left out because their channel was in a damaged chunk.
        source_complete: the source was already a finished file.
        problem: what was wrong with the source, one line (None if nothing).
        start_ns, end_ns: first and last ``log_time`` copied, ns.
    """

    src: Path
    dst: Path
    messages: int
    topics: int
    metadata: int
    attachments: int
    skipped_chunks: int
    orphaned: int
    source_complete: bool
    problem: str | None
    start_ns: int | None
    end_ns: int | None


@contextlib.contextmanager
def _open_mcap(path: Path) -> Iterator[tuple[ClampedFile, int]]:
    try:
        f = open(path, "rb")  # noqa: SIM115 - closed below, after the caller's block
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}") from None
    with f:
        size = check_magic(f, path)
        yield ClampedFile(f, size), size


_DECIMAL = re.compile(r"[0-9]{1,19}\Z")


def unix_offset_from(metadata: Mapping[str, Mapping[str, str]], where: str | Path) -> int | None:
    """The offset recorded in a log's ``metadata`` records (by name), ns; None if none is.

    Raises:
        InputError: at ``where``: the value is not a decimal integer in [0, 2^63).
    """
    record = metadata.get(_topics.CLOCK_METADATA)
    if record is None or _topics.UNIX_OFFSET_KEY not in record:
        return None
    value = record[_topics.UNIX_OFFSET_KEY]
    if not _DECIMAL.match(value) or int(value) >= 2**63:
        raise InputError(where, f"metadata {_topics.CLOCK_METADATA}.{_topics.UNIX_OFFSET_KEY}: "
                                f"expected an integer number of ns >= 0, got {value[:40]!r}")
    return int(value)


def _recorded_offset(f: ClampedFile, size: int, path: Path) -> int | None:
    """The offset recorded in the finished file ``f`` (its summary was checked)."""
    f.seek(0)
    clock = {m.name: m.metadata for m in SeekingReader(f, record_size_limit=size).iter_metadata()
             if m.name == _topics.CLOCK_METADATA}
    return unix_offset_from(clock, path)


def log_info(path: str | Path) -> LogInfo:
    """Summarise the MCAP file at ``path``: from its summary if finished, else by scanning.

    Raises:
        InputError: the file is missing, unreadable or not MCAP (one line naming it).
    """
    path = Path(path)
    with _open_mcap(path) as (f, size):
        found = _checked_summary(f, size)
        if isinstance(found, str):
            return _info_from_scan(f, path, size, found)
        header, summary = found
        if summary.statistics is None:
            return _info_from_scan(f, path, size)
        try:
            offset = _recorded_offset(f, size, path)
        except READ_ERRORS as e:
            return _info_from_scan(f, path, size, f"damaged metadata: {e}")
        return _info_from_summary(path, size, header, summary, summary.statistics, offset)


def _info_from_summary(path: Path, size: int, header: Header, summary: Summary,
                       stats: Statistics, offset: int | None) -> LogInfo:
    """The info of a finished file from its checked summary and its statistics."""
    counts = stats.channel_message_counts
    has_messages = stats.message_count > 0
    return _log_info(path, size, header.library, True, None, summary.schemas,
                     summary.channels.values(), counts,
                     stats.message_start_time if has_messages else None,
                     stats.message_end_time if has_messages else None,
                     [m.name for m in summary.metadata_indexes], offset)


def _checked_summary(f: ClampedFile, size: int) -> tuple[Header, Summary] | str:
    """The header and the summary of a finished file, or why there is none to trust
    (one line): no footer, no summary, or one that does not add up
    (:func:`~shared.logs._chunks.check_summary`)."""
    unfinished = "no summary or index (the writer never finished the file)"
    f.seek(size - len(MAGIC))
    finished = size >= 2 * len(MAGIC) and f.read(len(MAGIC)) == MAGIC
    f.seek(0)
    if not finished:
        return unfinished
    try:
        reader = SeekingReader(f, record_size_limit=size)
        header = reader.get_header()
        summary = reader.get_summary()
        if summary is None:
            return unfinished
        check_summary(summary, size)
    except READ_ERRORS as e:
        return f"damaged summary: {e}"
    return header, summary


def _info_from_scan(f: ClampedFile, path: Path, size: int,
                    summary_problem: str | None = None) -> LogInfo:
    """The info of any file by reading its data section; ``summary_problem`` is why its
    summary was not used, reported if the data section itself is whole."""
    f.seek(0)
    scan = RecordScan(f, size)
    library = ""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    counts: Counter[int] = Counter()
    times: list[int] = []
    metadata: list[str] = []
    offset: int | None = None
    for record in scan.records():
        if isinstance(record, Header):
            library = record.library
        elif isinstance(record, Schema):
            schemas[record.id] = record
        elif isinstance(record, Channel):
            channels[record.id] = record
        elif isinstance(record, Message):
            counts[record.channel_id] += 1
            times.append(record.log_time)
        elif isinstance(record, Metadata):
            metadata.append(record.name)
            if record.name == _topics.CLOCK_METADATA:
                offset = unix_offset_from({record.name: record.metadata}, path)
    problem = scan.problem or (summary_problem if scan.complete else None)
    if scan.skipped_chunks:
        problem = f"{problem}; {scan.skipped_chunks} damaged chunk(s) skipped"
    return _log_info(path, size, library, False, problem, schemas, channels.values(), counts,
                     min(times, default=None), max(times, default=None), metadata, offset)


def _log_info(path: Path, size: int, library: str, complete: bool, problem: str | None,
              schemas: dict[int, Schema], channels: Iterable[Channel], counts: dict[int, int],
              start_ns: int | None, end_ns: int | None, metadata: list[str],
              offset: int | None) -> LogInfo:
    duration_s = 0.0 if start_ns is None or end_ns is None else (end_ns - start_ns) / 1e9
    topics = sorted((TopicInfo(
        topic=c.topic,
        schema_name=schemas[c.schema_id].name if c.schema_id in schemas else "",
        message_encoding=c.message_encoding,
        message_count=counts.get(c.id, 0),
        rate_hz=counts.get(c.id, 0) / duration_s if duration_s > 0 else 0.0,
    ) for c in channels), key=lambda t: t.topic)
    return LogInfo(path=path, size_bytes=size, library=library, complete=complete,
                   problem=problem, message_count=sum(counts.values()), start_ns=start_ns,
                   end_ns=end_ns, topics=tuple(topics), metadata=tuple(metadata),
                   unix_offset_ns=offset)


def read_messages(path: str | Path, topics: Iterable[str] | None = None) -> Iterator[LogMessage]:
    """The JSON messages of the finished MCAP file at ``path``, in log time order, each
    with its time on the writer's clock (the module docstring's "Times").

    Args:
        path: the file.
        topics: only these topics (all when None).

    Raises:
        InputError: the file is missing, not MCAP, unfinished, truncated or damaged, or a
            message is not JSON (one line naming the file; unfinished files name the fix).
    """
    path = Path(path)
    with _open_mcap(path) as (f, size):
        found = _checked_summary(f, size)
        if isinstance(found, str):
            raise InputError(path, f"{_info_from_scan(f, path, size, found).problem}; "
                             + RECOVER_HINT.format(path=path))
        summary = found[1]
        if not summary.chunk_indexes and (summary.statistics is None
                                          or summary.statistics.message_count):
            raise InputError(path, "its messages are not in indexed chunks; "
                             + RECOVER_HINT.format(path=path))
        selected = None if topics is None else set(topics)
        try:
            offset = _recorded_offset(f, size, path) or 0
            for schema, channel, message in messages_in_time_order(f, summary, selected):
                if channel.message_encoding != MessageEncoding.JSON:
                    raise InputError(path, f"{channel.topic}: message encoding "
                                     f"{channel.message_encoding!r} is not json")
                where = f"{path}: {channel.topic} message {message.sequence}"
                data = parse_json(where, message.data, InputError, int_bits=MESSAGE_INT_BITS)
                if not isinstance(data, dict):
                    raise InputError(where, f"expected a JSON object, got {type(data).__name__}")
                yield LogMessage(channel.topic, schema.name if schema else "", message.log_time,
                                 message.publish_time, message.sequence, data,
                                 message.log_time - offset)
        except READ_ERRORS as e:
            raise InputError(path, f"damaged: {e}; " + RECOVER_HINT.format(path=path)) from None


def read_metadata(path: str | Path) -> dict[str, dict[str, str]]:
    """The metadata records of the finished MCAP file at ``path`` by name (the last of a
    name wins), e.g. ``{"run": {"route": "east_a", ...}}``.

    Raises:
        InputError: as :func:`read_messages`.
    """
    path = Path(path)
    with _open_mcap(path) as (f, size):
        found = _checked_summary(f, size)
        if isinstance(found, str):
            raise InputError(path, f"{_info_from_scan(f, path, size, found).problem}; "
                             + RECOVER_HINT.format(path=path))
        f.seek(0)
        try:
            return {m.name: dict(m.metadata)
                    for m in SeekingReader(f, record_size_limit=size).iter_metadata()}
        except READ_ERRORS as e:
            raise InputError(path, f"damaged: {e}; " + RECOVER_HINT.format(path=path)) from None


def recover(src: str | Path, dst: str | Path) -> RecoverReport:
    """Rewrite the MCAP file ``src`` into a valid, indexed ``dst``, keeping what is intact.

    Every message of every intact chunk is copied with its times and sequence number,
    along with schemas, channels, metadata and attachments. ``src`` is only read;
    ``dst`` is written to a temporary file first and replaced at the end.

    Raises:
        InputError: ``src`` is missing or not MCAP, ``dst`` is ``src``, or ``dst``
            cannot be written (one line naming the file).
    """
    src, dst = Path(src), Path(dst)
    if dst.resolve() == src.resolve():
        raise InputError(dst, "the output must be another file (recover never changes its input)")
    with _open_mcap(src) as (f, size):
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{dst.name}.", suffix=".tmp", dir=dst.parent)
        except OSError as e:
            raise InputError(dst, f"cannot write: {e.strerror}") from None
        try:
            with os.fdopen(fd, "wb") as out:
                report = _copy(RecordScan(f, size), out, src, dst)
                out.flush()
                os.fsync(out.fileno())
            os.replace(tmp, dst)
        except OSError as e:
            os.unlink(tmp)
            raise InputError(dst, f"cannot write: {e.strerror}") from None
        except BaseException:
            os.unlink(tmp)
            raise
    return report


def _copy(scan: RecordScan, out: IO[bytes], src: Path, dst: Path) -> RecoverReport:
    writer = Writer(out, compression=CompressionType.LZ4)
    started = False
    schema_ids: dict[int, int] = {}
    channel_ids: dict[int, int] = {}
    counts = Counter[str]()
    times: list[int] = []
    for record in scan.records():
        if not started:
            header = record if isinstance(record, Header) else Header("", "")
            writer.start(profile=header.profile, library=header.library or "unknown")
            started = True
        if isinstance(record, Schema) and record.id not in schema_ids:
            schema_ids[record.id] = writer.register_schema(record.name, record.encoding,
                                                           record.data)
        elif isinstance(record, Channel) and record.id not in channel_ids:
            channel_ids[record.id] = writer.register_channel(
                record.topic, record.message_encoding, schema_ids.get(record.schema_id, 0),
                record.metadata)
        elif isinstance(record, Message):
            if record.channel_id not in channel_ids:
                counts["orphaned"] += 1
                continue
            writer.add_message(channel_ids[record.channel_id], record.log_time, record.data,
                               record.publish_time, record.sequence)
            times.append(record.log_time)
        elif isinstance(record, Metadata):
            writer.add_metadata(record.name, record.metadata)
            counts["metadata"] += 1
        elif isinstance(record, Attachment):
            writer.add_attachment(record.create_time, record.log_time, record.name,
                                  record.media_type, record.data)
            counts["attachments"] += 1
    if not started:
        writer.start(profile="", library="unknown")
    writer.finish()
    complete = scan.complete and scan.problem is None and not scan.skipped_chunks
    return RecoverReport(
        src=src, dst=dst, messages=len(times), topics=len(channel_ids),
        metadata=counts["metadata"], attachments=counts["attachments"],
        skipped_chunks=scan.skipped_chunks, orphaned=counts["orphaned"],
        source_complete=complete, problem=scan.problem,
        start_ns=min(times, default=None), end_ns=max(times, default=None))
