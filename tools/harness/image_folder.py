"""A folder of images as ``vmnav calibrate`` reads it: every file in a format OpenCV reads
and :mod:`shared.image_decode` checks, sorted by name with numbers in numeric order, all of
one size."""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import CalibrationError

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

#: File name endings read as images.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".jpe", ".pgm", ".ppm", ".pbm", ".pnm", ".bmp", ".dib",
                  ".tif", ".tiff", ".webp")


def image_paths(folder: Path) -> list[Path]:
    """The images of ``folder``, sorted by name, numbers in it by value (2.jpg before 10.jpg)."""
    if not folder.exists():
        raise CalibrationError(folder, "folder not found")
    if not folder.is_dir():
        raise CalibrationError(folder, "not a folder")
    try:
        paths = sorted(
            (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES),
            key=lambda p: [int(part) if part.isdigit() else part
                           for part in re.split(r"(\d+)", p.name)],
        )
    except OSError as e:
        raise CalibrationError(folder, f"cannot list the folder: {e.strerror}") from None
    if not paths:
        raise CalibrationError(folder, f"no images ({', '.join(IMAGE_SUFFIXES)}) in this folder")
    return paths


def read_images(paths: list[Path]) -> tuple[list[NDArray[np.uint8]], tuple[int, int]]:
    """The images as (H, W) uint8 grey, and their common ``(width, height)``."""
    from shared.image_decode import FILE_FORMATS, read_grey

    images = []
    for path in paths:
        image = read_grey(path, error=CalibrationError, formats=FILE_FORMATS)
        if images and image.shape != images[0].shape:
            (h, w), (h0, w0) = image.shape, images[0].shape
            raise CalibrationError(path, f"image is {w}x{h} but {paths[0].name} is {w0}x{h0}")
        images.append(image)
    height, width = images[0].shape
    return images, (width, height)
