"""Strict JSON files: parse errors and non-standard numbers become one-line input errors."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from shared.errors import InputError


def parse_json(path: Path, text: str, error: type[InputError]) -> Any:
    """Parse ``text`` read from ``path``, refusing NaN and Infinity (not JSON numbers).

    Args:
        path: the file the text came from, for the message.
        text: the file's content.
        error: the :class:`InputError` subclass to raise (e.g. ``CalibrationError``).

    Raises:
        error: ``"<path>: not valid JSON (truncated?): <what> at line L column C"``.
    """
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except json.JSONDecodeError as e:
        raise error(
            path, f"not valid JSON (truncated?): {e.msg} at line {e.lineno} column {e.colno}"
        ) from None
    except ValueError as e:
        raise error(path, f"not valid JSON: {e}") from None


def _refuse_constant(name: str) -> float:
    raise ValueError(f"{name} is not a JSON number")
