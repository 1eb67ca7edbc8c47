"""Strict JSON: parse errors, deep nesting and out-of-range numbers become one-line input errors.

The one JSON parser for what vmnav reads from files (memory manifests, calibration and
parameter files, the JSON messages of MCAP logs). Beyond :func:`json.loads` it refuses,
before anything reaches the caller:

* nesting deeper than ``max_depth`` arrays and objects, checked on the text before
  parsing (so a file of ``[[[[...`` gives an error, not a ``RecursionError``);
* integers outside [-2^63, 2^63) by default (``10**400`` would overflow every float
  conversion downstream; log messages allow [-2^128, 2^128) for random generator
  states) and numbers too large for a float (``1e400`` parses as inf);
* NaN and Infinity, which are not JSON numbers.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

from shared.errors import InputError

MAX_DEPTH = 32
"""Deepest nesting of arrays and objects accepted by default; vmnav's own files nest at
most 4 deep."""
INT_BITS = 63
"""Integers in [-2^INT_BITS, 2^INT_BITS) are accepted by default: int64, enough for every
count, id and time in ns."""

_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)
_BRACKET = re.compile(r"[\[\]{}]")


def parse_json(
    path: str | Path,
    text: str | bytes,
    error: type[InputError],
    max_depth: int = MAX_DEPTH,
    int_bits: int = INT_BITS,
) -> Any:
    """Parse ``text`` read from ``path`` under the rules of the module docstring.

    Args:
        path: the file (or ``file: record``) the text came from, for the message.
        text: the content, text or UTF-8 bytes.
        error: the :class:`InputError` subclass to raise (e.g. ``CalibrationError``).
        max_depth: the deepest nesting of arrays and objects allowed.
        int_bits: integers must lie in [-2^int_bits, 2^int_bits).

    Raises:
        error: ``"<path>: not valid JSON (truncated?): <what> at line L column C"``, or
            ``"<path>: not valid JSON: <what>"`` for bad UTF-8, nesting deeper than
            ``max_depth``, an out-of-range number, NaN or Infinity.
    """
    try:
        if isinstance(text, bytes | bytearray):
            text = bytes(text).decode("utf-8")
        _check_depth(text, max_depth)
        return json.loads(text, parse_constant=_refuse_constant,
                          parse_int=lambda literal: _checked_int(literal, int_bits),
                          parse_float=_checked_float)
    except json.JSONDecodeError as e:
        raise error(
            path, f"not valid JSON (truncated?): {e.msg} at line {e.lineno} column {e.colno}"
        ) from None
    except UnicodeDecodeError as e:
        raise error(path, f"not valid JSON: not UTF-8 text (byte {e.start})") from None
    except ValueError as e:
        raise error(path, f"not valid JSON: {e}") from None


def _check_depth(text: str, max_depth: int) -> None:
    """Raise ValueError if arrays and objects outside strings nest deeper than ``max_depth``."""
    depth = 0
    for bracket in _BRACKET.findall(_STRING.sub("", text)):
        depth += 1 if bracket in "[{" else -1
        if depth > max_depth:
            raise ValueError(f"arrays and objects nest more than {max_depth} deep")


def _checked_int(literal: str, bits: int) -> int:
    limit = 2**bits
    # longer literals than the limit's (and a sign) are refused before int() converts them
    value = int(literal) if len(literal) <= len(str(limit)) + 1 else None
    if value is None or not -limit <= value < limit:
        raise ValueError(f"integer {_abridged(literal)} is outside [-2^{bits}, 2^{bits})")
    return value


def _checked_float(literal: str) -> float:
    value = float(literal)
    if not math.isfinite(value):
        raise ValueError(f"number {_abridged(literal)} is too large for a float")
    return value


def _abridged(literal: str) -> str:
    return literal if len(literal) <= 24 else f"{literal[:12]}...({len(literal)} characters)"


def _refuse_constant(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number")
