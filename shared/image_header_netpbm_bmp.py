"""The header of a Netpbm (PBM, PGM, PPM) or BMP file, read and checked without decoding.

The companion of :mod:`shared.image_header` (same rules, same :class:`ImageHeader`) for
two formats that OpenCV reads and that calibration images often come in (PGM from
machine-vision cameras and datasets, BMP from Windows tools). Only files the user
names on the command line are read in these formats (:data:`FILE_FORMATS`); images
from a peer or a memory stay PNG or JPEG (:data:`shared.image_decode.WIRE_FORMATS`).

Rules:

1. Netpbm (netpbm.sourceforge.net, pbm/pgm/ppm pages): magic ``P1``-``P6``, then width,
   height and (except for bitmaps, P1/P4) maxval in ASCII decimal, separated by
   whitespace and ``#`` comments, then one whitespace byte and the raster. Netpbm has no
   compression: the raster of a binary file (P4-P6) must be in the file in full
   (``ceil(W/8) H``, ``W H`` or ``3 W H`` samples, two bytes each when maxval > 255),
   and a plain (ASCII) file needs at least a byte per sample.
2. BMP (Microsoft's BITMAPFILEHEADER and BITMAPCOREHEADER/BITMAPINFOHEADER and its
   V4/V5 extensions): ``BM``, the pixel data offset, a DIB header of 12, 40, 52, 56,
   108 or 124 bytes, one plane, 1/4/8/16/24/32 bits per pixel, compression none,
   RLE8 (8 bits), RLE4 (4 bits) or bit fields (16/32 bits). An uncompressed raster
   (rows padded to 4 bytes) must fit in the file from its offset; an RLE raster is
   held to the caller's pixel budget like any other picture.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

from shared.errors import InputError
from shared.image_header import ImageFormat, ImageHeader

NETPBM_MAGICS = (b"P1", b"P2", b"P3", b"P4", b"P5", b"P6")
BMP_MAGIC = b"BM"

#: Longest Netpbm header read (comments included), bytes.
MAX_NETPBM_HEADER_BYTES = 4096
#: One Netpbm header field: whitespace and comments, then at most 10 digits.
_NETPBM_FIELD = re.compile(rb"(?:[ \t\r\n\v\f]|#[^\r\n]*)+(\d{1,10})(?!\d)")
_BMP_DIB_SIZES = (12, 40, 52, 56, 108, 124)
#: compression -> bits per pixel it allows (BI_RGB, BI_RLE8, BI_RLE4, BI_BITFIELDS).
_BMP_COMPRESSIONS = {0: (1, 4, 8, 16, 24, 32), 1: (8,), 2: (4,), 3: (16, 32)}


def read_netpbm_or_bmp_header(data: bytes, where: str | Path,
                              error: type[InputError] = InputError) -> ImageHeader:
    """Walk the header of the Netpbm or BMP file ``data`` (module docstring).

    Args:
        data: the whole file, starting with ``P1``-``P6`` or ``BM``.
        where: the file the bytes came from, for errors.
        error: the :class:`InputError` subclass to raise.

    Returns:
        The picture's header; the pixels are not looked at.

    Raises:
        InputError: (``error``) neither format, or a header that is malformed or
            declares more raster than the file holds; one line.
    """
    if data[:2] in NETPBM_MAGICS:
        return _netpbm_header(data, where, error)
    if data.startswith(BMP_MAGIC):
        return _bmp_header(data, where, error)
    start = data[:8].hex(" ") if data else "nothing"
    raise error(where, f"not a Netpbm or BMP image (the file starts with {start})")


def _netpbm_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    kind = data[1] - ord("0")
    bitmap, plain = kind in (1, 4), kind <= 3
    head = data[:MAX_NETPBM_HEADER_BYTES]
    fields, pos = [], 2
    for name in ("width", "height") if bitmap else ("width", "height", "maxval"):
        match = _NETPBM_FIELD.match(head, pos)
        if match is None:
            raise error(where, f"corrupt Netpbm P{kind}: no {name} at byte {pos}")
        fields.append(int(match[1]))
        pos = match.end()
    width, height = fields[0], fields[1]
    maxval = 1 if bitmap else fields[2]
    if width < 1 or height < 1:
        raise error(where, f"corrupt Netpbm P{kind}: declares {width}x{height} px")
    if not 1 <= maxval <= 65535:
        raise error(where, f"corrupt Netpbm P{kind}: maxval {maxval} is not in 1..65535")
    if pos >= len(data) or data[pos] not in b" \t\r\n\v\f":
        raise error(where, f"corrupt Netpbm P{kind}: no whitespace before the raster at "
                           f"byte {pos}")
    channels = 3 if kind in (3, 6) else 1
    depth = 1 if bitmap else 8 if maxval <= 255 else 16
    if plain:
        need = width * height * channels
    elif bitmap:
        need = (width + 7) // 8 * height
    else:
        need = width * height * channels * depth // 8
    have = len(data) - pos - 1
    if have < need:
        raise error(where, f"corrupt Netpbm P{kind}: {width}x{height} px need {need} bytes of "
                           f"raster, the file has {have}")
    return ImageHeader(ImageFormat.NETPBM, width, height, channels, depth)


def _bmp_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    def corrupt(problem: str) -> InputError:
        return error(where, f"corrupt BMP: {problem}")

    if len(data) < 26:
        raise corrupt(f"{len(data)} bytes, shorter than its headers")
    (offset,) = struct.unpack_from("<I", data, 10)
    (dib_size,) = struct.unpack_from("<I", data, 14)
    if dib_size not in _BMP_DIB_SIZES:
        raise corrupt(f"DIB header of {dib_size} bytes (known: "
                      f"{', '.join(map(str, _BMP_DIB_SIZES))})")
    if len(data) < 14 + dib_size:
        raise corrupt(f"{len(data)} bytes, shorter than its {dib_size}-byte DIB header")
    if dib_size == 12:
        width, height, planes, bpp = struct.unpack_from("<HHHH", data, 18)
        compression = 0
    else:
        width, height, planes, bpp, compression = struct.unpack_from("<iiHHI", data, 18)
    rows = abs(height)  # a negative height is a top-down raster
    if width < 1 or rows < 1:
        raise corrupt(f"declares {width}x{height} px")
    if planes != 1:
        raise corrupt(f"{planes} planes (must be 1)")
    if bpp not in _BMP_COMPRESSIONS.get(compression, ()):
        raise corrupt(f"compression {compression} with {bpp} bits per pixel is not a BMP "
                      "OpenCV reads")
    if not 14 + dib_size <= offset <= len(data):
        raise corrupt(f"pixel data offset {offset} is outside bytes {14 + dib_size}.."
                      f"{len(data)}")
    if compression in (0, 3):
        need = (width * bpp + 31) // 32 * 4 * rows
        if len(data) - offset < need:
            raise corrupt(f"{width}x{rows} px of {bpp} bits need {need} bytes of pixel data "
                          f"from byte {offset}, the file has {len(data) - offset}")
    return ImageHeader(ImageFormat.BMP, width, rows, 4 if bpp == 32 else 3, bpp)
