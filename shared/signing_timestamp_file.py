"""The signing timestamp file: what a signing end keeps across restarts.

The MAVLink signing spec asks every signing end to keep its timestamp in persistent
storage and to start from the larger of it and its clock. The file holds a
:class:`~shared.mavlink.signing.SigningTimestamps` (our own timestamp and each
stream's last accepted one) as the JSON of
:func:`~shared.mavlink.signing.timestamps_to_json`; reading and writing it is the
only I/O here. Writes are atomic (``shared.atomic_file``): a crash leaves the
previous file.
"""

from __future__ import annotations

from pathlib import Path

from shared.atomic_file import write_bytes_atomic
from shared.errors import InputError
from shared.json_file import parse_json
from shared.mavlink.signing import SigningTimestamps, timestamps_from_json, timestamps_to_json


def read_timestamp_file(path: str | Path) -> SigningTimestamps | None:
    """The timestamps kept in ``path``; None when there is no file yet (a first start).

    Raises:
        InputError: the file cannot be read, or is not a timestamp file (names it and
            what is wrong).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        return None
    except OSError as e:
        raise InputError(path, f"cannot read signing timestamp file: {e.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(path, "signing timestamp file is not UTF-8 text") from None
    return timestamps_from_json(path, parse_json(path, text, InputError))


def write_timestamp_file(path: str | Path, saved: SigningTimestamps) -> None:
    """Replace ``path`` with ``saved``, atomically.

    Raises:
        InputError: the folder is missing or cannot be written (names the path).
    """
    write_bytes_atomic(path, timestamps_to_json(saved))
