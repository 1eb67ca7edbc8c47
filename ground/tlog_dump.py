"""``vmnav log dump``: pymavlink's own ``mavlogdump`` with the vmnav dialect.

pymavlink's tools load a dialect by name: ``mavutil.set_dialect(NAME)`` imports
``pymavlink.dialects.v20.NAME`` (``v10`` without ``MAVLINK20`` in the environment) and,
when that module is missing, generates it from ``NAME.xml`` found beside pymavlink's
dialects or under ``$MDEF/v1.0/``, writing the module into pymavlink's installed package.
Our dialect is neither there nor should be written there (a site-packages folder is often
read-only, and shared by every project in it), so the stock ``mavlogdump.py`` prints our
messages as ``UNKNOWN_24400`` and ``--dialect vmnav`` fails in the generator.

:func:`register_dialect` makes our generated module (:mod:`shared.mavlink.vmnav_dialect`,
mavgen's output for ``shared/mavlink/vmnav.xml``) importable under pymavlink's name, in
this process only, no file written; :func:`run_mavlogdump` then runs pymavlink's
``pymavlink.tools.mavlogdump`` (the module ``mavlogdump.py`` is installed from) as its
``__main__`` with ``--dialect vmnav``, so every option of it works as documented by
pymavlink.
"""

from __future__ import annotations

import contextlib
import runpy
import sys
from collections.abc import Sequence

#: The dialect's name for pymavlink (``--dialect``).
DIALECT = "vmnav"
#: pymavlink's module name of a MAVLink 2 dialect.
PYMAVLINK_MODULE = f"pymavlink.dialects.v20.{DIALECT}"
#: Our message ids (shared/mavlink/vmnav.xml).
VMNAV_IDS = range(24400, 24500)


def register_dialect() -> None:
    """Make ``mavutil.set_dialect("vmnav")`` load our dialect, in this process.

    Idempotent. Sets ``MAVLINK20`` (by importing :mod:`shared.mavlink.dialect`), since
    the dialect is MAVLink 2 only.
    """
    import pymavlink.dialects.v20 as v20

    from shared.mavlink.dialect import mavlink

    sys.modules[PYMAVLINK_MODULE] = mavlink
    setattr(v20, DIALECT, mavlink)


def run_mavlogdump(argv: Sequence[str]) -> int:
    """Run pymavlink's ``mavlogdump`` on ``argv`` (its options and the log) with our dialect.

    Args:
        argv: ``mavlogdump.py``'s arguments, e.g. ``["--types", "VISUAL_SERVO_STATUS",
            "ground-20261129-022058.tlog"]``; ``--dialect vmnav`` is put first (a later
            ``--dialect`` wins, as argparse goes).

    Returns:
        Its exit status (0 when it ran to the end).
    """
    register_dialect()
    saved = sys.argv
    sys.argv = ["mavlogdump.py", "--dialect", DIALECT, *argv]
    try:
        runpy.run_module("pymavlink.tools.mavlogdump", run_name="__main__", alter_sys=True)
    except SystemExit as e:
        return e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
    finally:
        sys.argv = saved
        with contextlib.suppress(Exception):
            sys.stdout.flush()
    return 0
