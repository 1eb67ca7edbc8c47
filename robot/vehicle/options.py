"""Where the vehicle endpoint keeps its files, and its signing setup."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True, slots=True)
class VehicleFiles:
    """The endpoint's files.

    Attributes:
        memory_dir: the visual memory, served read-only over FTP as ``/memory``.
        upload_dir: where FTP uploads land (``/upload``: the goal photos); created if missing.
        param_file: the parameters set from the ground, rewritten atomically after each set.
    """

    memory_dir: Path
    upload_dir: Path
    param_file: Path


@dataclass(frozen=True, slots=True)
class SigningSetup:
    """MAVLink 2 signing of the link (``shared.mavlink.signing``).

    Attributes:
        key: the 32-byte secret (``shared.key_file.read_key_file`` reads one).
        unix_offset_ns: Unix time minus the endpoint's clock reading, ns, measured once by
            the entry point (``time.time_ns() - clock.now_ns()``); keeps the outgoing
            signing timestamp at the wall clock.
        link_id: this link's id in signed packets, 0..255.
        timestamp_file: where the signing timestamps are kept across restarts
            (``shared.signing_timestamp_file``; the robot's is ``STATE/signing-timestamps.json``);
            None keeps them only in memory.

    ``VehicleEndpoint`` raises ValueError for a key that is not 32 bytes or a link id
    out of range (``configure_signing``).
    """

    key: bytes
    unix_offset_ns: int
    link_id: int = 0
    timestamp_file: Path | None = None
