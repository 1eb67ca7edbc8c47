"""``vmnav vision ...``: look at the vision front end on one's own images.

Each subcommand is a module of its own with ``add_parser(vision_sub)`` and its ``run``;
:data:`SUBCOMMANDS` lists them, so a new subcommand is one more module and one more entry
(``vmnav vision pair``: :mod:`tools.vision_pair_cmd`).
"""

from __future__ import annotations

import argparse

from tools import vision_localize_cmd, vision_pair_cmd

#: The modules of the subcommands, each with ``add_parser(vision_sub)``.
SUBCOMMANDS = (vision_pair_cmd, vision_localize_cmd)


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav vision`` and its subcommands."""
    vision = subparsers.add_parser(
        "vision", help="the front end on your own images: matches, relative pose")
    vision_sub = vision.add_subparsers(dest="vision_command", metavar="SUBCOMMAND",
                                       required=True)
    for module in SUBCOMMANDS:
        module.add_parser(vision_sub)
