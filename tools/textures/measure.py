"""Measure a texture set: load time on one core, sizes, coverage, seams; prints JSON.

Run::

    python -m tools.textures.measure [--manifest FILE] [--repeats N]

``load_s_median`` is the median time of :meth:`TextureLibrary.load` (every picture
decoded and checked, every procedural texture generated) on one core.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from sim.texture_library import KINDS, TextureLibrary
from tools.bench.cpu import pin_to_one_core
from tools.textures.seamless import seam_ratio


def measure(manifest: Path, repeats: int) -> dict[str, Any]:
    """The figures of the set at ``manifest`` (see the module's docstring)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        library = TextureLibrary.load(manifest)
        times.append(time.perf_counter() - t0)
    textures = [library.get(n) for n in library.names()]
    tiling = [t for t in textures if t.tiles]
    files = [p for p in manifest.parent.rglob("*") if p.is_file()]
    density = [min(t.px_per_m) for t in textures]
    return {
        "textures": len(textures),
        "by_kind": {k: len(library.names(k)) for k in KINDS},
        "tiling": len(tiling),
        "load_s_median": round(statistics.median(times), 3),
        "load_s": [round(t, 3) for t in times],
        "files_mb": round(sum(p.stat().st_size for p in files) / 1e6, 2),
        "decoded_mb": round(sum(t.image.nbytes for t in textures) / 1e6, 2),
        "seam_ratio_max": round(max(seam_ratio(t.image) for t in tiling), 3),
        "px_per_m_min": round(min(density), 1),
        "px_per_m_median": round(statistics.median(density), 1),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.textures.measure",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--manifest", type=Path, help="a texture set (default: the built-in)")
    parser.add_argument("--repeats", type=int, default=7, help="loads to time [default: 7]")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        print(f"--repeats: must be >= 1, got {args.repeats}", file=sys.stderr)
        return 2
    cpus = pin_to_one_core()
    if args.manifest is not None:
        figures = measure(args.manifest, args.repeats)
    else:
        with resources.as_file(resources.files("sim") / "textures" / "textures.toml") as path:
            figures = measure(path, args.repeats)
    print(json.dumps({"cpus": cpus, **figures}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
