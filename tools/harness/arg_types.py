"""Types for the command line's numbers: a bad value is argparse's one-line usage error.

``type=int`` lets ``--seed -1`` or ``--people -3`` through to a traceback deep in the
simulator, and ``type=float`` accepts ``nan`` and ``inf``. Each type here parses and
checks, and raises :class:`argparse.ArgumentTypeError`, which argparse prints as
``vmnav sim snapshot: error: argument --seed: must be an integer >= 0, got '-1'``
(exit status 2).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def integer(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """An integer in ``[minimum, maximum]`` (no upper bound when ``maximum`` is None)."""
    bounds = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"

    def parse(text: str) -> int:
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer {bounds}, got {text!r}") from None
        if value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"must be an integer {bounds}, got {text!r}")
        return value

    parse.__name__ = "integer"  # argparse names the type in some messages
    return parse


def number(minimum: float | None = None, maximum: float | None = None, *,
           above: bool = False) -> Callable[[str], float]:
    """A finite number, at least ``minimum`` (more than it when ``above``) and at most
    ``maximum`` where they are given."""
    bounds = []
    if minimum is not None:
        bounds.append(f"{'>' if above else '>='} {minimum:g}")
    if maximum is not None:
        bounds.append(f"<= {maximum:g}")
    wanted = " ".join(["a finite number", " and ".join(bounds)]).rstrip()

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text!r}") from None
        if (not math.isfinite(value)
                or (minimum is not None and (value <= minimum if above else value < minimum))
                or (maximum is not None and value > maximum)):
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text!r}")
        return value

    parse.__name__ = "number"
    return parse


COUNT = integer(0)
"""How many of something, possibly none (people, ...)."""
POSITIVE_COUNT = integer(1)
"""How many of something, at least one (frames, seeds, queries, repeats ...)."""
SEED = integer(0)
"""A seed of numpy's random generators (negative seeds are refused there)."""
KEY_IMAGE = integer(0, 2**31 - 1)
"""A key image id (MAVLink carries them in int32 fields)."""
SYSTEM_ID = integer(1, 255)
"""A MAVLink system id (0 is the broadcast address)."""
FINITE = number()
"""Any finite number (a coordinate on the floor plan, an angle ...)."""
POSITIVE = number(0.0, above=True)
"""A finite number > 0 (a duration, a speed bound ...)."""
NON_NEGATIVE = number(0.0)
"""A finite number >= 0 (a tolerance ...)."""
COVERAGE = number(0.0, 1.0, above=True)
"""A share in (0, 1] (of an image covered ...)."""
