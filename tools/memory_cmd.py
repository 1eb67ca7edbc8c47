"""``vmnav memory ...``: inspect a visual memory on disk.

Each subcommand is a pair of functions here, ``add_<name>_parser(memory_sub)``
and ``run_<name>(args)``; :data:`SUBCOMMANDS` lists the parser builders, so a new
subcommand is one more pair and one more entry.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory`` and its subcommands."""
    memory = subparsers.add_parser("memory", help="inspect a visual memory")
    memory_sub = memory.add_subparsers(dest="memory_command", metavar="SUBCOMMAND", required=True)
    for add_subcommand in SUBCOMMANDS:
        add_subcommand(memory_sub)


def add_info_parser(memory_sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav memory info DIR``."""
    info = memory_sub.add_parser(
        "info",
        help="paths, key images, spacing, junctions and connectivity of a memory",
        description="Read and validate the visual memory in DIR and print its paths (key "
        "images, length, key image spacing), its junctions and whether it is strongly "
        "connected, naming the key images that are not.",
    )
    info.add_argument("directory", type=Path, metavar="DIR", help="the memory's folder")
    info.add_argument("--json", action="store_true", help="print the summary as JSON")
    info.set_defaults(run=run_info)


def run_info(args: argparse.Namespace) -> int:
    """Print the summary of the memory in ``args.directory``."""
    from shared.memory import memory_summary, read_memory, summary_text

    summary = memory_summary(read_memory(args.directory))
    print(json.dumps(summary, indent=2) if args.json else summary_text(summary))
    return 0


SUBCOMMANDS = (add_info_parser,)
