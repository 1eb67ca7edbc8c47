"""``vmnav bench hostile``: issue 15's attacks on the real parts, one after the other.

Each part is a module ``tools.bench.hostile_<part>`` whose ``measure(seed)`` runs the
real thing (processes, sockets, files; our code on both ends) and returns its figures
and ``targets_met``:

========  ====================================================================  ========
part      what                                                                  time
========  ====================================================================  ========
messages  the issue's MISSION_ITEMs and 3000 random messages against a live     ~15 s
          vehicle; HOLD obeyed and heartbeats after
signing   wrong keys, replays (also across a restart), old timestamps, the      ~5 s
          lockout of the real station
traffic   a 20 s flood against a signed ``vmnav robot`` with our station; FTP   ~60 s
          cache after 65,025 peers, replies per request
stall     the control loop stalled 3 s while driving at 0.2 m/s: time to the   ~10 s
          stop, distance driven
images    the image bombs through the robot's photo path: peak RSS              ~10 s
files     hostile memories and MCAP logs through the real commands: peak RSS    ~60 s
sim       hostile ARIA packets and HTTP requests against ``vmnav sim serve``    ~20 s
========  ====================================================================  ========

The JSON maps each part to its figures, and ``targets_met`` is whether every part met its
own; ``vmnav bench all`` also checks the headline figures of every part against the one
table of targets (:mod:`tools.bench.targets`).
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import time
from collections.abc import Sequence
from typing import Any

#: Every part, in the order they run.
PARTS = ("messages", "signing", "traffic", "stall", "images", "files", "sim")


def bench_hostile(parts: Sequence[str], seed: int) -> dict[str, Any]:
    """Run ``parts`` (of :data:`PARTS`) in order; ``{part: figures + wall_s}``."""
    result: dict[str, Any] = {}
    for part in parts:
        module = importlib.import_module(f"tools.bench.hostile_{part}")
        start = time.monotonic()
        figures = module.measure(seed)
        result[part] = {**figures, "wall_s": round(time.monotonic() - start, 1)}
    return result


def run(args: argparse.Namespace) -> int:
    """Print the hostile-input benchmark's JSON (``vmnav bench hostile``)."""
    from tools.bench.names import picked

    parts = list(PARTS) if args.parts is None else picked("--parts", args.parts, list(PARTS),
                                                          "part")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_hostile(parts, args.seed)
    met = all(figures["targets_met"] for figures in result.values())
    print(json.dumps({"benchmark": "hostile", "load_average_at_start": load, "seed": args.seed,
                      **result, "targets_met": met}, indent=2))
    return 0
