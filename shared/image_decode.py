"""Decoding images that come from outside: the header is checked before any pixel is.

Theory of operation
-------------------

Every PNG or JPEG the project reads from a peer, an upload or a file it did not write
itself (a photo goal, a memory's key images, a log's camera frames) goes through
:func:`decode_grey` (or :func:`read_grey` for a file):

1. the file's size is capped (:data:`MAX_FILE_BYTES`) before it is read;
2. its structure is walked (:func:`shared.image_header.read_image_header`): every
   declared length is checked against the bytes there, so a bogus chunk length cannot
   make the decoder allocate or read gigabytes. A user's own files (calibration
   images, ``formats=FILE_FORMATS``) may also be Netpbm, BMP, TIFF or WebP, walked by
   :mod:`shared.image_header_files`;
3. the declared picture is held to the caller's pixel budget (at most
   :data:`MAX_PIXELS`, each side at most :data:`MAX_SIDE_PX`; a photo goal's budget
   comes from the camera, :func:`photo_pixel_limit`), so a decompression bomb is
   refused before a byte is inflated;
4. only then OpenCV decodes it, to grey.

Memory: OpenCV allocates the grey picture (1 byte per pixel) and, for a progressive
JPEG, a coefficient buffer of 2 bytes per pixel per component; at :data:`MAX_PIXELS`
that is at most ~300 MB, for a camera-sized photo a few MB. Time: the decode is linear
in the pixels and the file's bytes, both bounded, and the scans of a JPEG are capped
(:data:`shared.image_header.MAX_JPEG_SCANS`): the worst photo within an 800x600
camera's budget (a 1600x1200 progressive JPEG of noise at quality 100, 2.7 MB) takes
about 0.13 s to walk and decode. OpenCV releases the GIL while it decodes, so a decode
on a worker thread does not hold up the robot's loop; with time and memory bounded by
the header, a hard wall-clock limit (a child process per photo) would only add an
OpenCV import, ~0.3 s and ~100 MB, to every photo.

OpenCV's own cap (the ``OPENCV_IO_MAX_IMAGE_PIXELS`` environment variable, 2^30 pixels
by default) is read once when ``cv2`` is imported and has no setter; the checks here
do not rely on it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from shared.errors import InputError
from shared.image_header import (
    JPEG_SOI,
    PNG_SIGNATURE,
    ImageFormat,
    ImageHeader,
    read_image_header,
)
from shared.image_header_files import MAGICS, read_file_image_header

#: Largest picture decoded, pixels (~33.5 Mpx, a 6700x5000 photo).
MAX_PIXELS = 1 << 25
#: Longest side decoded, px: bounds the decoders' row buffers.
MAX_SIDE_PX = 1 << 15
#: Largest image file read, bytes.
MAX_FILE_BYTES = 64 << 20
#: A photo goal may have this many times the camera's pixels (it must then be of the
#: camera's size to be localized; the margin only keeps the message about its size).
PHOTO_PIXELS_PER_CAMERA_PIXEL = 4

GreyImage = npt.NDArray[np.uint8]  # (H, W) uint8

#: What comes from a peer, an upload or a memory: PNG or JPEG only.
WIRE_FORMATS = frozenset({ImageFormat.PNG, ImageFormat.JPEG})
#: What a user's own files may be (calibration images): also Netpbm (PGM...), BMP, TIFF
#: and WebP.
FILE_FORMATS = frozenset(ImageFormat)


def photo_pixel_limit(width_px: int, height_px: int) -> int:
    """The pixel budget for a photo meant for a ``width_px`` x ``height_px`` camera.

    Returns:
        :data:`PHOTO_PIXELS_PER_CAMERA_PIXEL` times the camera's pixels, at most
        :data:`MAX_PIXELS`.
    """
    return min(MAX_PIXELS, PHOTO_PIXELS_PER_CAMERA_PIXEL * width_px * height_px)


def check_image(data: bytes, where: str | Path, max_pixels: int = MAX_PIXELS,
                error: type[InputError] = InputError,
                formats: frozenset[ImageFormat] = WIRE_FORMATS) -> ImageHeader:
    """The header of the image ``data``, once checked against the limits.

    Args:
        data: the whole file.
        where: the file (or message) the bytes came from, for errors.
        max_pixels: the caller's budget, pixels (at most :data:`MAX_PIXELS` is used).
        error: the :class:`InputError` subclass to raise.
        formats: the formats accepted (:data:`WIRE_FORMATS` or :data:`FILE_FORMATS`).

    Returns:
        The picture's header.

    Raises:
        InputError: (``error``) too big a file, not of ``formats``, a broken structure,
            or a picture over the budget; one line naming what is wrong.
    """
    if len(data) > MAX_FILE_BYTES:
        raise error(where, f"{len(data)} bytes, more than the {MAX_FILE_BYTES} an image "
                           f"file may have")
    local = formats - WIRE_FORMATS
    if local and data.startswith(MAGICS):
        header = read_file_image_header(data, where, error)
        if header.format not in formats:
            raise error(where, f"{header.format.value} images are not accepted here")
    elif local and not data.startswith((PNG_SIGNATURE, JPEG_SOI)):
        names = ", ".join(f.value for f in ImageFormat if f in formats)
        start = data[:8].hex(" ") if data else "nothing"
        raise error(where, f"not an image of a format read here ({names}; the file starts "
                           f"with {start})")
    else:
        header = read_image_header(data, where, error)
    size = f"{header.format.value} of {header.width_px}x{header.height_px} px"
    if max(header.width_px, header.height_px) > MAX_SIDE_PX:
        raise error(where, f"{size}: a side is longer than {MAX_SIDE_PX} px")
    budget = min(max_pixels, MAX_PIXELS)
    if header.pixels > budget:
        raise error(where, f"{size}: {header.pixels} pixels, more than the {budget} allowed")
    return header


def decode_grey(data: bytes, where: str | Path, max_pixels: int = MAX_PIXELS,
                error: type[InputError] = InputError,
                formats: frozenset[ImageFormat] = WIRE_FORMATS) -> GreyImage:
    """Decode the image ``data`` to grey, once :func:`check_image` passed.

    Args:
        data: the whole file.
        where: the file (or message) the bytes came from, for errors.
        max_pixels: the caller's budget, pixels (at most :data:`MAX_PIXELS` is used).
        error: the :class:`InputError` subclass to raise.
        formats: the formats accepted (:data:`WIRE_FORMATS` or :data:`FILE_FORMATS`).

    Returns:
        (H, W) uint8 grey picture (colour converted, 16-bit reduced to 8, alpha dropped,
        turned upright as its Exif orientation says), of the header's pixels.

    Raises:
        InputError: (``error``) refused by :func:`check_image`, or pixel data OpenCV
            cannot decode.
    """
    import cv2

    header = check_image(data, where, max_pixels, error, formats)
    try:
        image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
    except cv2.error as e:
        raise error(where, f"corrupt {header.format.value}: OpenCV refused it "
                           f"({str(e).strip().splitlines()[-1]})") from None
    # An Exif orientation (JPEG) turns the picture a quarter turn: W x H then.
    if image is None or image.shape not in ((header.height_px, header.width_px),
                                            (header.width_px, header.height_px)):
        raise error(where, f"corrupt {header.format.value}: its pixel data cannot be decoded")
    return image


def read_grey(path: Path, max_pixels: int = MAX_PIXELS,
              error: type[InputError] = InputError,
              formats: frozenset[ImageFormat] = WIRE_FORMATS) -> GreyImage:
    """Read the image file at ``path`` and decode it to grey (:func:`decode_grey`).

    At most :data:`MAX_FILE_BYTES` + 1 bytes are read, whatever the file's size.

    Raises:
        InputError: (``error``) the file cannot be read, or :func:`decode_grey` refused it.
    """
    try:
        with path.open("rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except OSError as e:
        raise error(path, f"cannot read the image: {e.strerror}") from None
    return decode_grey(data, path, max_pixels, error, formats)
