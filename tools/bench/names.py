"""Name lists given on the ``vmnav bench`` command line (``--only``, ``--cases``)."""

from __future__ import annotations


def picked(option: str, text: str, known: list[str], kind: str) -> list[str]:
    """The names of the comma-separated ``text``, each one of ``known``.

    Raises:
        InputError: a name is not known, or there is none (names ``option``).
    """
    from shared.errors import InputError

    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in known]
    if unknown or not names:
        what = f"unknown {kind} {', '.join(unknown)}" if unknown else f"no {kind}"
        raise InputError(option, f"{what} (known: {', '.join(known)})")
    return names
