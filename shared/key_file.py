"""The MAVLink signing key file both the robot and the ground station are given (``--key``).

Reading the file is the only I/O here; what its bytes mean (raw key, hex or
passphrase) is :func:`shared.mavlink.signing.key_from_file_bytes`.
"""

from __future__ import annotations

from pathlib import Path

from shared.errors import InputError
from shared.mavlink.signing import key_from_file_bytes


def read_key_file(path: str | Path) -> bytes:
    """Read a signing key (formats: :mod:`shared.mavlink.signing`).

    Returns:
        The 32-byte key.

    Raises:
        InputError: the file is missing, unreadable, empty, or neither a raw key
            nor hex nor a printable passphrase long enough (the message says which).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(path, "signing key file not found") from None
    except OSError as e:
        raise InputError(path, f"cannot read signing key file: {e.strerror}") from None
    return key_from_file_bytes(path, raw)
