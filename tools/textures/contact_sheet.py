"""A contact sheet of a texture set: every texture with its name, kind and size.

Run::

    python -m tools.textures.contact_sheet docs/img/textures.png [--manifest FILE]

A tiling texture is shown repeated 2 x 2 (so a seam would show as a cross in the
middle of its cell); the others once, letterboxed.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from sim.texture_library import KINDS, TextureLibrary

CELL_PX = 150
LABEL_PX = 30
COLUMNS = 10


def contact_sheet(library: TextureLibrary) -> np.ndarray:
    """The sheet: (rows * (CELL_PX + LABEL_PX), COLUMNS * CELL_PX) uint8, by kind then name."""
    names = [n for kind in KINDS for n in library.names(kind)]
    rows = -(-len(names) // COLUMNS)
    sheet = np.full((rows * (CELL_PX + LABEL_PX), COLUMNS * CELL_PX), 255, np.uint8)
    for i, name in enumerate(names):
        texture = library.get(name)
        image = np.tile(texture.image, (2, 2)) if texture.tiles else texture.image
        h, w = image.shape
        scale = (CELL_PX - 6) / max(h, w)
        thumb = cv2.resize(image, (max(1, round(w * scale)), max(1, round(h * scale))),
                           interpolation=cv2.INTER_AREA)
        th, tw = thumb.shape
        y0 = (i // COLUMNS) * (CELL_PX + LABEL_PX)
        x0 = (i % COLUMNS) * CELL_PX
        oy, ox = y0 + (CELL_PX - th) // 2, x0 + (CELL_PX - tw) // 2
        sheet[oy:oy + th, ox:ox + tw] = thumb
        size = f"{texture.kind} {texture.size_m[0]:g}x{texture.size_m[1]:g} m"
        cv2.putText(sheet, name, (x0 + 3, y0 + CELL_PX + 11), cv2.FONT_HERSHEY_SIMPLEX, 0.38,
                    0, 1, cv2.LINE_AA)
        cv2.putText(sheet, size, (x0 + 3, y0 + CELL_PX + 25), cv2.FONT_HERSHEY_SIMPLEX, 0.33,
                    90, 1, cv2.LINE_AA)
    return sheet


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.textures.contact_sheet",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--manifest", type=Path, help="a texture set (default: the built-in)")
    args = parser.parse_args(argv)
    library = (TextureLibrary.load(args.manifest) if args.manifest is not None
               else TextureLibrary.builtin())
    if not cv2.imwrite(str(args.out), contact_sheet(library)):
        print(f"{args.out}: cannot write the picture", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
