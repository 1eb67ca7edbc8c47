"""Command-line options that say what changed between teach and repeat (:mod:`sim.scene_change`).

``vmnav demo`` and ``vmnav bench follow`` take them; ``--people`` (who walks about
during the repeat) is with the simulation's options (:mod:`tools.harness.sim_args`).

``--lighting`` takes a comma-separated list of changes::

    scale=F        the whole scene's light times F for the whole repeat (0.6: dimmer)
    lamps-off=F    that share of the lit lamps switched off (F in [0, 1], or "all")
    hour=H         daylight at solar hour H (the world as taught: noon; 18: dusk)
    step=F@T       the light times F from T seconds into the repeat on (a switch)

``--doors`` takes ``NAME=open``, ``NAME=closed`` or ``NAME=DEG`` (the opening, degrees),
comma-separated; ``--removed`` a fraction of the movable pictures or names of pictures
and objects.
"""

from __future__ import annotations

import argparse
import logging
from typing import TYPE_CHECKING

from shared.errors import InputError

if TYPE_CHECKING:
    from sim.config import SimConfig
    from sim.scene_change import LightingChange, SceneChange

#: What ``--landmark-dropout`` (removed) is answered with.
DROPOUT_REMOVED = ("was removed: the fiducial landmarks are gone; say what changed with "
                   "--lighting, --moved, --removed, --doors and --people")

_LIGHTING_KEYS = ("scale", "lamps-off", "hour", "step")

_log = logging.getLogger(__name__)


def add_change_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--lighting``, ``--moved``, ``--removed`` and ``--doors`` (and the removed
    ``--landmark-dropout``, which only answers with :data:`DROPOUT_REMOVED`)."""
    group = parser.add_argument_group(
        "what changed since the teach", "the repeat's world differs from the taught one")
    group.add_argument(
        "--lighting", metavar="CHANGES",
        help="light changes, comma-separated: scale=F (the scene's light times F), "
        "lamps-off=F|all (share of the lamps off), hour=H (daylight at solar hour H; taught "
        "at 12), step=F@T (times F from T s into the repeat on); e.g. "
        "lamps-off=0.5,hour=17,step=0.6@30")
    group.add_argument(
        "--moved", type=float, default=0.0, metavar="F",
        help="fraction of the movable objects moved (displaced up to 1 m and turned up to "
        "45 degrees in free space, never near a route) [default: 0]")
    group.add_argument(
        "--removed", metavar="F|NAME,...",
        help="pictures taken away: a fraction of the movable ones, or the pictures and "
        "objects named")
    group.add_argument(
        "--doors", metavar="NAME=STATE,...",
        help="doors set: NAME=open (90 degrees), NAME=closed or NAME=DEG")
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
    removed_fraction, removed = _removed_from_text(args.removed)
    doors = () if args.doors is None else doors_from_text(args.doors)
    for option, fields in (("--moved", {"moved_fraction": args.moved}),
                           ("--removed", {"removed_fraction": removed_fraction}),
                           ("--doors", {"doors": doors})):
        try:
            SceneChange(**fields)  # type: ignore[arg-type]
        except ValueError as e:
            raise InputError(option, str(e)) from None
    return SceneChange(lighting=lighting, moved_fraction=args.moved,
                       removed_fraction=removed_fraction, removed=removed, doors=doors)


def check_change_fits(change: SceneChange, sim_config: SimConfig) -> None:
    """Refuse a change the world cannot take (no such door, a door closed across a route,
    an unknown name...) before minutes of teaching; warn about a share that picks nothing
    (``--moved 0.2`` in a world with two movable objects or none).

    Raises:
        InputError: one line naming what does not fit; ConfigError: a bad world.
    """
    from sim.scene_change import movable_indices
    from sim.world import load_world
    from tools.harness.demo import changed_world

    if change.is_none:
        return
    world = load_world(sim_config.world)
    changed_world(world, change, sim_config.seed)
    shares = (("--lighting lamps-off", change.lighting.lamps_off, "lit lamps",
               sum(lamp.on for lamp in world.lamps)),
              ("--moved", change.moved_fraction, "movable objects", len(movable_indices(world))),
              ("--removed", change.removed_fraction, "movable pictures",
               sum(p.movable for p in world.pictures)))
    for option, share, things, count in shares:
        if share > 0 and round(share * count) == 0:
            _log.warning("%s %g changes nothing: world '%s' has %d %s", option, share,
                         world.name, count, things)


def lighting_from_text(text: str) -> LightingChange:
    """Parse ``--lighting`` (see the module docstring).

    Raises:
        InputError: an unknown key, a repeated key, a malformed or out-of-range value.
    """
    from sim.scene_change import LightingChange

    values = _pairs("--lighting", text)
    for key in values:
        if key not in _LIGHTING_KEYS:
            raise InputError("--lighting", f"unknown change {key!r} (known: "
                             f"{', '.join(k + '=...' for k in _LIGHTING_KEYS)})")
    fields: dict[str, float] = {}
    if "scale" in values:
        fields["scale"] = _number("--lighting", "scale", values["scale"])
    if "lamps-off" in values:
        text_off = values["lamps-off"]
        fields["lamps_off"] = 1.0 if text_off == "all" else _number("--lighting", "lamps-off",
                                                                     text_off)
    if "hour" in values:
        fields["hour"] = _number("--lighting", "hour", values["hour"])
    if "step" in values:
        factor, at, time_s = values["step"].partition("@")
        if not at:
            raise InputError("--lighting", f"step wants FACTOR@SECONDS, got {values['step']!r}")
        fields["step_factor"] = _number("--lighting", "step", factor)
        fields["step_at_s"] = _number("--lighting", "step", time_s)
    try:
        return LightingChange(**fields)
    except ValueError as e:
        raise InputError("--lighting", str(e)) from None


def doors_from_text(text: str) -> tuple[tuple[str, float], ...]:
    """Parse ``--doors``: (name, opening in degrees) per door.

    Raises:
        InputError: a malformed item or a state that is not open, closed or a number.
    """
    from sim.scene_change import OPEN_DEG

    doors = []
    for name, state in _pairs("--doors", text).items():
        if state == "open":
            doors.append((name, OPEN_DEG))
        elif state == "closed":
            doors.append((name, 0.0))
        else:
            doors.append((name, _number("--doors", name, state)))
    return tuple(doors)


def _removed_from_text(text: str | None) -> tuple[float, tuple[str, ...]]:
    """``--removed``: (fraction, ()) for a number, (0, names) otherwise."""
    if text is None:
        return 0.0, ()
    try:
        return float(text), ()
    except ValueError:
        names = tuple(name.strip() for name in text.split(",") if name.strip())
        if not names:
            raise InputError("--removed", "names nothing") from None
        return 0.0, names


def _pairs(option: str, text: str) -> dict[str, str]:
    """``KEY=VALUE,...`` as a dict (keys once each).

    Raises:
        InputError: an item without ``=``, an empty key or a key given twice.
    """
    values: dict[str, str] = {}
    for item in (part.strip() for part in text.split(",")):
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(option, f"{item!r} is not KEY=VALUE")
        if key in values:
            raise InputError(option, f"{key} is given twice")
        values[key] = value.strip()
    return values


def _number(option: str, key: str, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InputError(option, f"{key}: {text.strip()!r} is not a number") from None
