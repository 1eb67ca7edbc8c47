"""Measure a texture set: load time on one core, sizes, coverage, seams; prints JSON.

Run::

    python -m tools.textures.measure [--manifest FILE] [--repeats N]

``load_s_median`` is the median time of :meth:`TextureLibrary.load` (every picture
decoded and checked, every procedural texture generated) on one core.

``corners_per_m2`` says how much the paper's front end finds on each texture: the
picture resampled to ``--view-px-per-m`` (174 px/m: the default lens, about 174 px/rad,
1 m from the surface), Harris corners found by :func:`robot.vision.features.detect_harris`
with the default :class:`robot.config.FeatureConfig` but no cap on their number,
divided by the picture's area; pictures smaller than 32 px at that scale are left out.
Each picture is measured alone: the detector's threshold is relative to the picture's
strongest corner, so a bland picture (plaster) counts weak corners that a whole frame
with a poster in it would not.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from robot.config import FeatureConfig
from robot.vision.features import detect_harris
from sim.texture_library import BUILTIN_MANIFEST, KINDS, Texture, TextureLibrary
from tools.bench.cpu import pin_to_one_core
from tools.textures.seamless import seam_ratio

#: The default lens's scale on a surface 1 m away, px/m (shared/camera_model.py: ~174 px/rad).
VIEW_PX_PER_M = 174.0
_SMALLEST_VIEW_PX = 32


def corners_per_m2(texture: Texture, view_px_per_m: float) -> float | None:
    """Harris corners per square metre of ``texture`` seen at ``view_px_per_m``, or None
    if the picture is under 32 px at that scale."""
    w_px = round(texture.size_m[0] * view_px_per_m)
    h_px = round(texture.size_m[1] * view_px_per_m)
    if min(w_px, h_px) < _SMALLEST_VIEW_PX:
        return None
    view = cv2.resize(texture.image, (w_px, h_px), interpolation=cv2.INTER_AREA)
    config = dataclasses.replace(FeatureConfig(), max_corners=w_px * h_px)
    found = detect_harris(np.ascontiguousarray(view), config)
    return len(found.pixels_xy) / (texture.size_m[0] * texture.size_m[1])


def measure(manifest: Path, repeats: int, view_px_per_m: float = VIEW_PX_PER_M
            ) -> dict[str, Any]:
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
    corners = {t.name: c for t in textures
               if (c := corners_per_m2(t, view_px_per_m)) is not None}
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
        "view_px_per_m": view_px_per_m,
        "corners_per_m2_median_by_kind": {
            k: round(statistics.median(v), 1) for k in KINDS
            if (v := [c for n, c in corners.items() if library.get(n).kind == k])},
        "corners_per_m2_fewest": {n: round(c, 1) for n, c in
                                  sorted(corners.items(), key=lambda nc: nc[1])[:5]},
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.textures.measure",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--manifest", type=Path, help="a texture set (default: the built-in)")
    parser.add_argument("--repeats", type=int, default=7, help="loads to time [default: 7]")
    parser.add_argument("--view-px-per-m", type=float, default=VIEW_PX_PER_M,
                        help=f"scale of the corner count, px/m [default: {VIEW_PX_PER_M:g}]")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        print(f"--repeats: must be >= 1, got {args.repeats}", file=sys.stderr)
        return 2
    if not args.view_px_per_m > 0:
        print(f"--view-px-per-m: must be > 0, got {args.view_px_per_m}", file=sys.stderr)
        return 2
    cpus = pin_to_one_core()
    manifest = args.manifest if args.manifest is not None else BUILTIN_MANIFEST
    figures = measure(manifest, args.repeats, args.view_px_per_m)
    print(json.dumps({"cpus": cpus, **figures}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
