"""MAVLink 2 message signing on pymavlink ``MAVLink`` objects (mavlink-vehicle.md §0.7, §1.9).

A signed packet carries ``link_id:u8 | timestamp:u48 | sha256(key + packet)[:6]``;
the timestamp counts 10 µs units since 2015-01-01 00:00 UTC. pymavlink checks
signatures while parsing (``MAVLink.check_signature``). This module adds what it
leaves to the application:

- **The key.** :func:`key_from_file_bytes` reads a key file's content (the file
  itself is read by ``shared/key_file.py``) as, in this order: exactly 32 bytes (the
  raw key); 64 hex digits; otherwise a passphrase (UTF-8 text, surrounding
  whitespace stripped, at least :data:`MIN_PASSPHRASE_CHARS` characters) whose
  SHA-256 is the key, as MAVProxy's ``signing key <passphrase>`` derives it. So a
  passphrase of exactly 32 bytes needs a trailing newline, or it is read raw.
- **Who may stay unsigned.** :class:`UnsignedPolicy` is the
  ``allow_unsigned_callback``: it accepts only the message ids it was given (none
  by default; never commands or mission messages) and counts what it rejects by
  message id. pymavlink itself counts packets in ``mav.signing``
  (:func:`signing_stats`); a rejected packet comes out of ``parse_buffer`` as
  BAD_DATA ("Invalid signature") when ``robust_parsing`` is set, else raises.
- **The check itself.** pymavlink's generated ``check_signature`` stores a stream's
  timestamp *before* it checks the signature, so a packet with a wrong key and a
  timestamp near 2**48 locks its (link id, system, component) stream out until restart:
  256 such packets, one per link id, shut out the real station. :func:`check_signature`
  is the same check in the safe order (the signature first, then the stream's and our
  own timestamps move) with a constant-time comparison;
  :class:`~shared.mavlink.dialect.MavlinkCodec` uses it.
- **Freshness.** A packet is accepted only with a timestamp above its stream's last
  (no replay), and a stream not heard before only within :data:`NEW_STREAM_WINDOW`
  (60 s) behind our own timestamp.
- **A current timestamp.** pymavlink adds 1 per packet sent, so after idle time its
  timestamp lags the wall clock, and peers reject a new stream more than 60 s old.
  :class:`SigningClock` raises it to the wall clock every ``period_ns`` (MAVProxy
  PR #1598 does so every 10 s).
- **Across restarts.** The spec asks a signing end to keep its timestamp in persistent
  storage and to start from the larger of it and the clock. :class:`SigningTimestamps`
  is what is kept: our own timestamp and every stream's last accepted one, so that
  after a restart no packet accepted before it is accepted again
  (:func:`restore_timestamps`; the file is ``shared/signing_timestamp_file.py``'s).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import secrets
import string
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from shared.clock import NS_PER_S
from shared.errors import InputError

#: Bytes in a signing key.
KEY_BYTES = 32
#: Shortest passphrase accepted in a key file, characters.
MIN_PASSPHRASE_CHARS = 8
#: Characters of a new passphrase (:func:`new_passphrase`): letters and digits, 62 of
#: them, so 43 carry 256 bits.
NEW_PASSPHRASE_CHARS = 43
#: The signing epoch, 2015-01-01 00:00:00 UTC, in Unix seconds.
EPOCH_UNIX_S = 1_420_070_400
#: Signing timestamp units per second (one unit is 10 µs).
TICKS_PER_S = 100_000
#: The timestamp field is 48 bits.
MAX_TIMESTAMP = (1 << 48) - 1
#: How far behind our own timestamp the first packet of a stream not heard before may
#: be, ticks (60 s, as pymavlink and the C library have it).
NEW_STREAM_WINDOW = 60 * TICKS_PER_S
#: Bytes of the signature block: link id (1), timestamp (6), signature (6).
SIGNATURE_BLOCK_BYTES = 13

#: A signing stream: (link id, system id, component id) of the sender.
Stream = tuple[int, int, int]


class MAVLink(Protocol):
    """Any pymavlink ``MAVLink`` object (every dialect's): its ``MAVLinkSigning`` state."""

    signing: Any


def key_from_passphrase(passphrase: str) -> bytes:
    """MAVProxy's key derivation: SHA-256 of the passphrase's bytes (32 bytes)."""
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


def new_passphrase() -> str:
    """A random passphrase of :data:`NEW_PASSPHRASE_CHARS` letters and digits (256 bits).

    MAVProxy takes keys only as a passphrase (``signing key <passphrase>``; a word of
    ASCII, the key its SHA-256), so a new key is one: its key file holds the passphrase
    and a newline, never 32 bytes or 64 hex digits.
    """
    alphabet = string.ascii_letters + string.digits
    return "".join(secrets.choice(alphabet) for _ in range(NEW_PASSPHRASE_CHARS))


def key_from_file_bytes(path: Path, raw: bytes) -> bytes:
    """The signing key a key file holds (see the module docstring for the three formats).

    Args:
        path: the file ``raw`` was read from, for the message.
        raw: the file's content.

    Returns:
        The 32-byte key.

    Raises:
        InputError: ``raw`` is empty, or neither a raw key nor hex nor a printable
            passphrase long enough (the message says which).
    """
    if len(raw) == KEY_BYTES:
        return raw
    try:
        text = raw.decode("utf-8").strip()
    except UnicodeDecodeError:
        text = None
    if text is None or not text.isprintable():
        raise InputError(path, f"signing key file holds {len(raw)} bytes that are not text: "
                               f"want a {KEY_BYTES}-byte raw key, 64 hex digits or a passphrase")
    if not text:
        raise InputError(path, "signing key file is empty")
    if len(text) == 2 * KEY_BYTES and all(c in string.hexdigits for c in text):
        return bytes.fromhex(text)
    if len(text) < MIN_PASSPHRASE_CHARS:
        raise InputError(path, f"signing passphrase is {len(text)} characters, "
                               f"at least {MIN_PASSPHRASE_CHARS} needed")
    return key_from_passphrase(text)


def timestamp_from_unix_ns(unix_ns: int) -> int:
    """Signing timestamp (10 µs units since 2015-01-01 UTC) of a Unix time in ns; >= 0."""
    return max(0, (unix_ns - EPOCH_UNIX_S * NS_PER_S) * TICKS_PER_S // NS_PER_S)


class UnsignedPolicy:
    """pymavlink's ``allow_unsigned_callback``: which unsigned (or badly signed) packets pass.

    Args:
        allowed_msg_ids: message ids let through unsigned, e.g. RADIO_STATUS (109)
            from a radio; empty rejects everything.
    """

    def __init__(self, allowed_msg_ids: Iterable[int] = ()) -> None:
        self.allowed_msg_ids = frozenset(allowed_msg_ids)
        self.rejected: Counter[int] = Counter()
        """Packets rejected so far, by message id."""

    def __call__(self, mav: MAVLink, msg_id: int) -> bool:
        if msg_id in self.allowed_msg_ids:
            return True
        self.rejected[msg_id] += 1
        return False

    @property
    def rejected_total(self) -> int:
        """Packets rejected so far."""
        return sum(self.rejected.values())


def configure_signing(mav: MAVLink, key: bytes, link_id: int, timestamp: int,
                      policy: UnsignedPolicy | None = None) -> UnsignedPolicy:
    """Sign everything ``mav`` packs and accept only signed packets (or ``policy``'s).

    Works on a ``MAVLink`` object; for a ``mavutil`` connection pass ``conn.mav``.

    Args:
        mav: the pymavlink codec object.
        key: the 32-byte secret key.
        link_id: this link's id, 0..255 (one per link so streams don't collide).
        timestamp: the starting timestamp, 10 µs units since 2015 (the persisted
            last one, or :func:`timestamp_from_unix_ns` of now).
        policy: the unsigned-packet policy; a new reject-all one by default.

    Returns:
        The policy installed, for its counters.

    Raises:
        ValueError: a key that is not 32 bytes, or a link id or timestamp out of range.
    """
    if len(key) != KEY_BYTES:
        raise ValueError(f"signing key is {len(key)} bytes, must be {KEY_BYTES}")
    if not 0 <= link_id <= 255:
        raise ValueError(f"signing link_id {link_id} outside 0..255")
    if not 0 <= timestamp <= MAX_TIMESTAMP:
        raise ValueError(f"signing timestamp {timestamp} outside 0..2**48-1")
    policy = policy if policy is not None else UnsignedPolicy()
    mav.signing.secret_key = bytes(key)
    mav.signing.sign_outgoing = True
    mav.signing.link_id = link_id
    mav.signing.timestamp = timestamp
    mav.signing.allow_unsigned_callback = policy
    return policy


def check_signature(signing: Any, msgbuf: bytes | bytearray, src_system: int,
                    src_component: int) -> bool:
    """Whether a signed packet is genuine and fresh; only then move the timestamps.

    pymavlink's ``check_signature`` with the order fixed (module docstring): the
    packet's stream timestamp must exceed the stream's last accepted one (or, for a
    stream not heard before, lie at most :data:`NEW_STREAM_WINDOW` behind
    ``signing.timestamp``), and its signature must match; only then do the stream's
    timestamp and ``signing.timestamp`` (our own, the larger of the two) move.

    Args:
        signing: a pymavlink ``MAVLinkSigning`` with its ``secret_key`` set.
        msgbuf: the whole packet, ending with its 13-byte signature block.
        src_system: the packet's system id.
        src_component: the packet's component id.
    """
    block = bytes(msgbuf[-SIGNATURE_BLOCK_BYTES:])
    timestamp = int.from_bytes(block[1:7], "little")
    stream = (block[0], src_system, src_component)
    last = signing.stream_timestamps.get(stream)
    if last is not None and timestamp <= last:
        return False
    if last is None and timestamp + NEW_STREAM_WINDOW < signing.timestamp:
        return False
    expected = hashlib.sha256(signing.secret_key + bytes(msgbuf[:-6])).digest()[:6]
    if not hmac.compare_digest(expected, block[7:]):
        return False
    signing.stream_timestamps[stream] = timestamp
    signing.timestamp = max(signing.timestamp, timestamp)
    return True


@dataclass(frozen=True, slots=True)
class SigningTimestamps:
    """What a signing end keeps across restarts (module docstring).

    Attributes:
        timestamp: our own signing timestamp, ticks (10 µs since 2015-01-01 UTC).
        streams: each stream's last accepted timestamp, ticks, by (link id, system id,
            component id) of its sender.
    """

    timestamp: int
    streams: Mapping[Stream, int]


def timestamps_of(mav: MAVLink) -> SigningTimestamps:
    """A copy of ``mav``'s signing timestamps, to keep."""
    return SigningTimestamps(int(mav.signing.timestamp), dict(mav.signing.stream_timestamps))


def restore_timestamps(mav: MAVLink, saved: SigningTimestamps) -> None:
    """Raise ``mav``'s own and stream timestamps to ``saved``'s (never lower one)."""
    signing = mav.signing
    signing.timestamp = max(signing.timestamp, saved.timestamp)
    for stream, timestamp in saved.streams.items():
        signing.stream_timestamps[stream] = max(signing.stream_timestamps.get(stream, 0),
                                                timestamp)


def timestamps_to_json(saved: SigningTimestamps) -> bytes:
    """``saved`` as UTF-8 JSON: ``{"timestamp": T, "streams": [[link, system, component,
    T], ...]}`` (ticks), streams sorted."""
    streams = sorted([*stream, t] for stream, t in saved.streams.items())
    return (json.dumps({"timestamp": saved.timestamp, "streams": streams}) + "\n").encode()


def timestamps_from_json(path: Path, document: object) -> SigningTimestamps:
    """The timestamps a parsed :func:`timestamps_to_json` document holds.

    Args:
        path: the file it came from, for the message.
        document: the parsed JSON.

    Raises:
        InputError: not that shape, or a number out of range (the message says where).
    """
    if not isinstance(document, dict) or set(document) != {"timestamp", "streams"}:
        raise InputError(path, 'signing timestamp file: want {"timestamp": T, "streams": [...]}')
    timestamp = document["timestamp"]
    if not _is_int_in(timestamp, MAX_TIMESTAMP):
        raise InputError(path, f"signing timestamp file: timestamp {timestamp!r} is not an "
                               "integer in 0..2**48-1")
    if not isinstance(document["streams"], list):
        raise InputError(path, "signing timestamp file: streams is not a list")
    streams: dict[Stream, int] = {}
    for i, entry in enumerate(document["streams"]):
        if (not isinstance(entry, list) or len(entry) != 4
                or not all(_is_int_in(v, 255) for v in entry[:3])
                or not _is_int_in(entry[3], MAX_TIMESTAMP)):
            raise InputError(path, f"signing timestamp file: streams[{i}] is not "
                                   "[link_id, system, component, timestamp] in range")
        streams[(entry[0], entry[1], entry[2])] = entry[3]
    return SigningTimestamps(timestamp, streams)


def _is_int_in(value: object, top: int) -> bool:
    """``value`` is an int (not a bool) in 0..``top``."""
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= top


@dataclass(frozen=True, slots=True)
class SigningStats:
    """pymavlink's signing counters for one ``MAVLink`` object (packets)."""

    signed: int  #: received with a signature
    good: int  #: signature valid
    bad: int  #: signature wrong, replayed or too old
    unsigned_accepted: int  #: unsigned or bad, let through by the policy
    rejected: int  #: unsigned or bad, dropped


def signing_stats(mav: MAVLink) -> SigningStats:
    """Read ``mav.signing``'s counters."""
    s = mav.signing
    return SigningStats(s.sig_count, s.goodsig_count, s.badsig_count, s.unsigned_count,
                        s.reject_count)


class SigningClock:
    """Keeps ``mav.signing.timestamp`` at least the wall clock's (module docstring).

    The clock given to a loop is monotonic with its own epoch, so wall time is
    ``now_ns + unix_offset_ns``; the entry point measures the offset once
    (``time.time_ns() - clock.now_ns()``). The timestamp never goes backwards.

    Args:
        mav: the signing ``MAVLink`` object.
        unix_offset_ns: Unix time minus the loop clock's reading, ns.
        period_ns: how often to bump, ns.
    """

    def __init__(self, mav: MAVLink, unix_offset_ns: int,
                 period_ns: int = 10 * NS_PER_S) -> None:
        if period_ns <= 0:
            raise ValueError(f"SigningClock period_ns must be > 0, got {period_ns}")
        self.mav = mav
        self.unix_offset_ns = unix_offset_ns
        self.period_ns = period_ns
        self._due_ns: int | None = None

    def get_timer(self) -> int | None:
        """When :meth:`handle_timer` should run next, ns; None before the first run."""
        return self._due_ns

    def handle_timer(self, now_ns: int) -> int:
        """Raise the timestamp to the wall clock's and schedule the next bump.

        Returns:
            The timestamp now in force (10 µs units since 2015).
        """
        wall = min(timestamp_from_unix_ns(now_ns + self.unix_offset_ns), MAX_TIMESTAMP)
        self.mav.signing.timestamp = max(self.mav.signing.timestamp, wall)
        self._due_ns = now_ns + self.period_ns
        return int(self.mav.signing.timestamp)
