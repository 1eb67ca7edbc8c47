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
- **A current timestamp.** pymavlink adds 1 per packet sent, so after idle time its
  timestamp lags the wall clock, and peers reject a new stream more than 60 s old.
  :class:`SigningClock` raises it to the wall clock every ``period_ns`` (MAVProxy
  PR #1598 does so every 10 s).
"""

from __future__ import annotations

import hashlib
import string
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from shared.clock import NS_PER_S
from shared.errors import InputError

#: Bytes in a signing key.
KEY_BYTES = 32
#: Shortest passphrase accepted in a key file, characters.
MIN_PASSPHRASE_CHARS = 8
#: The signing epoch, 2015-01-01 00:00:00 UTC, in Unix seconds.
EPOCH_UNIX_S = 1_420_070_400
#: Signing timestamp units per second (one unit is 10 µs).
TICKS_PER_S = 100_000
#: The timestamp field is 48 bits.
MAX_TIMESTAMP = (1 << 48) - 1


class MAVLink(Protocol):
    """Any pymavlink ``MAVLink`` object (every dialect's): its ``MAVLinkSigning`` state."""

    signing: Any


def key_from_passphrase(passphrase: str) -> bytes:
    """MAVProxy's key derivation: SHA-256 of the passphrase's bytes (32 bytes)."""
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


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
