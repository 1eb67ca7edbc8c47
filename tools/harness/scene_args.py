"""Command-line options that say what changed between teach and repeat (:mod:`sim.scene_change`).

``vmnav demo`` and ``vmnav bench follow`` take them; ``--people`` (who walks about
during the repeat) is with the simulation's options (:mod:`tools.harness.sim_args`).

``--lighting`` takes a comma-separated list of changes::

    scale=F        the whole scene's light times F for the whole repeat (0.6: dimmer)
    step=F@T       the light times F from T seconds into the repeat on (a switch)
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from shared.errors import InputError

if TYPE_CHECKING:
    from sim.scene_change import LightingChange, SceneChange

#: What ``--landmark-dropout`` (removed) is answered with.
DROPOUT_REMOVED = ("was removed: the fiducial landmarks are gone; say what changed with "
                   "--lighting, --moved and --people")

_LIGHTING_KEYS = ("scale", "step")


def add_change_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--lighting`` and ``--moved`` (and the removed ``--landmark-dropout``, which
    only answers with :data:`DROPOUT_REMOVED`)."""
    group = parser.add_argument_group(
        "what changed since the teach", "the repeat's world differs from the taught one")
    group.add_argument(
        "--lighting", metavar="CHANGES",
        help="light changes, comma-separated: scale=F (the scene's light times F), "
        "step=F@T (times F from T s into the repeat on); e.g. scale=0.7,step=0.5@20")
    group.add_argument(
        "--moved", type=float, default=0.0, metavar="F",
        help="fraction of the movable objects moved (displaced and turned in free space, "
        "never onto a route) [default: 0]")
    parser.add_argument("--landmark-dropout", help=argparse.SUPPRESS)


def scene_change_from_args(args: argparse.Namespace) -> SceneChange:
    """The scene change the options describe.

    Raises:
        InputError: a malformed or out-of-range option (naming it), or the removed
            ``--landmark-dropout``.
    """
    from sim.scene_change import LightingChange, SceneChange

    if args.landmark_dropout is not None:
        raise InputError("--landmark-dropout", DROPOUT_REMOVED)
    lighting = LightingChange() if args.lighting is None else lighting_from_text(args.lighting)
    try:
        return SceneChange(lighting=lighting, moved_fraction=args.moved)
    except ValueError as e:
        raise InputError("--moved", str(e)) from None


def lighting_from_text(text: str) -> LightingChange:
    """Parse ``--lighting`` (see the module docstring).

    Raises:
        InputError: an unknown key, a repeated key, a malformed or out-of-range value.
    """
    from sim.scene_change import LightingChange

    values: dict[str, str] = {}
    for item in (part.strip() for part in text.split(",")):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or key not in _LIGHTING_KEYS:
            raise InputError("--lighting", f"unknown change {item!r} (known: "
                             f"{', '.join(k + '=...' for k in _LIGHTING_KEYS)})")
        if key in values:
            raise InputError("--lighting", f"{key} is given twice")
        values[key] = value.strip()
    fields: dict[str, float] = {}
    if "scale" in values:
        fields["scale"] = _number("scale", values["scale"])
    if "step" in values:
        factor, at, time_s = values["step"].partition("@")
        if not at:
            raise InputError("--lighting", f"step wants FACTOR@SECONDS, got {values['step']!r}")
        fields["step_factor"] = _number("step", factor)
        fields["step_at_s"] = _number("step", time_s)
    try:
        return LightingChange(**fields)
    except ValueError as e:
        raise InputError("--lighting", str(e)) from None


def _number(key: str, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InputError("--lighting", f"{key}: {text.strip()!r} is not a number") from None
