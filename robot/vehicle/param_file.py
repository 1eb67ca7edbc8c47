"""Parameter values on disk: a small JSON file of the values set over MAVLink.

Format::

    {"format": "vmnav-params", "format_version": 1, "params": {"CTL_SPEED": 0.25}}

Only values that differ from their defaults are stored, so a new default (from
the robot's config file or a new release) applies wherever the operator never
set the parameter. Writes are atomic (``shared/atomic_file.py``). Loading
validates everything before touching the table: a corrupt file, an unknown name
or an out-of-range value raises :class:`ConfigError` naming the file, and
neither the table nor the file changes (the file is never rewritten on load).
"""

from __future__ import annotations

import json
from pathlib import Path

from shared.atomic_file import write_text_atomic
from shared.errors import ConfigError
from shared.json_file import parse_json
from shared.mavlink.params.table import ParamTable

FORMAT = "vmnav-params"
FORMAT_VERSION = 1


def load_param_file(path: str | Path, table: ParamTable) -> bool:
    """Apply the values stored in ``path`` to ``table``.

    Returns:
        False (and ``table`` unchanged) when the file does not exist yet, else True.

    Raises:
        ConfigError: ``"<path>: <problem>"``: unreadable, not JSON, wrong format or
            version, an unknown parameter, or a value its spec refuses.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return False
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(path, f"cannot read: {e}") from None
    data = parse_json(path, text, ConfigError)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ConfigError(path, f"not a parameter file (expected \"format\": {FORMAT!r})")
    version = data.get("format_version")
    if type(version) is not int or version != FORMAT_VERSION:
        raise ConfigError(path, f"format_version {version!r} is not supported "
                                f"(this vmnav reads {FORMAT_VERSION})")
    params = data.get("params")
    if not isinstance(params, dict):
        raise ConfigError(path, "params: expected an object of name: number")
    for name, value in params.items():
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(path, f"params.{name}: expected a number, got {value!r}")
        if (problem := table.problem(name, float(value))) is not None:
            raise ConfigError(path, f"params.{name}: {problem}")
    for name, value in params.items():
        table.set(name, float(value))
    return True


def save_param_file(path: str | Path, table: ParamTable) -> None:
    """Store the values of ``table`` that differ from their defaults, atomically.

    Raises:
        InputError: the folder does not exist or cannot be written (names the path).
    """
    changed = {spec.name: table.value(spec.name) for spec in table
               if table.value(spec.name) != spec.default}
    document = {"format": FORMAT, "format_version": FORMAT_VERSION, "params": changed}
    write_text_atomic(path, json.dumps(document, indent=2) + "\n")
