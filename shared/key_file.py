"""The MAVLink signing key file both the robot and the ground station are given (``--key``).

Reading and creating the file is the only I/O here; what its bytes mean (raw key, hex
or passphrase) is :func:`shared.mavlink.signing.key_from_file_bytes`, and a new key is
:func:`shared.mavlink.signing.new_passphrase`'s.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from shared.errors import InputError
from shared.mavlink.signing import key_from_file_bytes, new_passphrase

#: A key file's permissions: its owner reads and writes it, nobody else.
KEY_FILE_MODE = 0o600
#: Mode of the folders :func:`create_key_file` creates (owner only).
KEY_FOLDER_MODE = 0o700


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


def create_key_file(path: str | Path) -> None:
    """Write a new key (a random passphrase and a newline) to ``path``, mode 0600.

    Atomic and never overwriting: the key goes to a temporary 0600 file in the same
    folder, which is then linked as ``path`` (the link fails if ``path`` exists) and
    removed; readers see no file or the whole key. Missing folders are created, mode
    0700 (as ``ssh-keygen`` creates ``~/.ssh``).

    Raises:
        InputError: ``path`` exists, or its folder cannot be created or written.
    """
    path = Path(path)
    if path.exists() or path.is_symlink():
        raise InputError(path, "exists: a new key never replaces one (delete it first "
                               "if that is really what you want)")
    if path.parent.exists() and not path.parent.is_dir():
        raise InputError(path, f"cannot create key file: {path.parent} is not a folder")
    try:
        path.parent.mkdir(mode=KEY_FOLDER_MODE, parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as e:
        raise InputError(path, f"cannot create key file: {e.strerror}") from None
    try:
        with os.fdopen(fd, "w", encoding="ascii") as f:
            os.fchmod(f.fileno(), KEY_FILE_MODE)
            f.write(new_passphrase() + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.link(tmp, path)
    except FileExistsError:
        raise InputError(path, "exists: a new key never replaces one") from None
    except OSError as e:
        raise InputError(path, f"cannot create key file: {e.strerror}") from None
    finally:
        os.unlink(tmp)
