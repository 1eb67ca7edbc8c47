"""``vmnav ground keygen FILE``: a new MAVLink 2 signing key, and how to install it.

The key is a random passphrase (``shared.mavlink.signing.new_passphrase``), because
MAVProxy takes keys only that way; ``vmnav robot --key`` and ``vmnav ground --key``
read the same file. The file is created atomically with mode 0600 and never
replaces one; the passphrase is not printed, the instructions read it from the file.
It connects to nothing (its ``run`` replaces ``vmnav ground``'s).
"""

from __future__ import annotations

import argparse
from pathlib import Path

Subparsers = argparse._SubParsersAction  # type: ignore[type-arg]


def add_parser(sub: Subparsers) -> None:
    """Register ``vmnav ground keygen``."""
    keygen = sub.add_parser(
        "keygen", help="create a signing key file (mode 0600) and say how to install it",
        description="Create a MAVLink 2 signing key file for vmnav robot --key, vmnav ground "
        "--key and MAVProxy's signing module; connects to nothing.")
    keygen.add_argument("path", type=Path, metavar="FILE", help="the key file to create "
                        "(refused if it exists)")
    keygen.set_defaults(run=run)


def install_text(path: Path) -> str:
    """How to install the key in ``path`` on both sides, MAVProxy included (lines)."""
    name = path.name
    return "\n".join([
        f"vmnav ground keygen: wrote a new signing key to {path} (mode 0600, a 256-bit "
        "passphrase); keep it secret, copy it only over a safe channel (scp), keep 0600",
        f"  robot:    scp {path} ROBOT:{name}, then vmnav robot --key {name} ... "
        "(it listens on udpin:0.0.0.0:14550, signed; timestamps kept in --state)",
        f"  ground:   vmnav ground --key {path} --connect udpout:ROBOT:14550 SUBCOMMAND",
        f"  MAVProxy: echo \"udpout:ROBOT:14550 $(cat {path})\" >> ~/.mavproxy/signing.keys "
        "(the first word as given to --master), or `signing key PASSPHRASE` in its console; "
        "then `set allow_unsigned 0`. Not `signing setup`: vmnav robot takes its key from "
        "--key, not over the air (SETUP_SIGNING)",
    ])


def run(args: argparse.Namespace) -> int:
    """Create the key file and print how to install it."""
    from shared.key_file import create_key_file

    create_key_file(args.path)
    print(install_text(args.path))
    return 0
