"""Regenerate ``vmnav_dialect.py`` from ``vmnav.xml`` with pymavlink's mavgen.

Run ``python -m shared.mavlink.generate`` after editing ``vmnav.xml`` or upgrading
pymavlink, and commit the result; ``tests/shared/mavlink/test_dialect.py`` fails
while the committed module differs from what this produces.

mavgen resolves ``<include>`` relative to the including file's folder. Rather
than keep copies of common.xml, standard.xml and minimal.xml here, the XML is
staged in a temporary folder beside symlinks to pymavlink's bundled copies
(``pymavlink/dialects/v20``), so the include chain always matches the installed
pymavlink. The module header names files by basename only, so the staging folder
does not leak into the output.
"""

from __future__ import annotations

import contextlib
import io
import re
import sys
import tempfile
from pathlib import Path

from shared.errors import InputError

#: The dialect source.
XML_PATH = Path(__file__).with_name("vmnav.xml")
#: The committed generated module.
MODULE_PATH = Path(__file__).with_name("vmnav_dialect.py")

_INCLUDE = re.compile(r"<include>\s*([^<\s]+)\s*</include>")


def bundled_dialects_dir() -> Path:
    """pymavlink's folder of MAVLink 2 dialect XML (common.xml and its includes)."""
    import pymavlink

    return Path(pymavlink.__file__).parent / "dialects" / "v20"


def generate_dialect(output: Path, xml_path: Path = XML_PATH) -> None:
    """Generate the Python dialect module for ``xml_path`` into ``output``.

    Args:
        output: the ``.py`` file to write; its stem becomes the dialect name, so
            keep ``vmnav_dialect.py`` for byte-identical output.
        xml_path: the dialect XML; its includes resolve against pymavlink's copies.

    Raises:
        InputError: mavgen refused the XML (message names the file and carries
            mavgen's own output).
    """
    from pymavlink.generator import mavgen, mavparse

    bundled = bundled_dialects_dir()
    with tempfile.TemporaryDirectory(prefix="vmnav-mavgen-") as tmp:
        staged = Path(tmp) / xml_path.name
        staged.write_bytes(xml_path.read_bytes())
        _link_includes(xml_path, bundled, Path(tmp))
        opts = mavgen.Opts(str(output), wire_protocol=mavparse.PROTOCOL_2_0,
                           language="Python3", validate=True)
        log = io.StringIO()
        try:
            with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
                ok = mavgen.mavgen(opts, [str(staged)])
        except SystemExit:  # mavgen exits on an invalid included file
            ok = False
        if not ok:
            raise InputError(xml_path, f"mavgen failed: {_last_lines(log.getvalue())}")


def _link_includes(xml_path: Path, bundled: Path, staging: Path) -> None:
    """Symlink, into ``staging``, every file ``xml_path`` includes, transitively."""
    pending = _INCLUDE.findall(xml_path.read_text(encoding="utf-8"))
    while pending:
        name = pending.pop()
        target = staging / name
        if target.exists():
            continue
        source = bundled / name
        if not source.is_file():
            raise InputError(xml_path, f"includes {name}, which pymavlink does not bundle")
        target.symlink_to(source)
        pending.extend(_INCLUDE.findall(source.read_text(encoding="utf-8")))


def _last_lines(text: str, n: int = 3) -> str:
    lines = [line for line in text.splitlines() if line.strip()]
    return " | ".join(lines[-n:]) if lines else "no output"


def main() -> int:
    """Regenerate :data:`MODULE_PATH`; print one line on failure and return 1."""
    try:
        generate_dialect(MODULE_PATH)
    except InputError as e:
        print(e, file=sys.stderr)
        return 1
    print(f"wrote {MODULE_PATH}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
