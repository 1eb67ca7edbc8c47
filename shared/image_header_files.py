"""The header of a Netpbm, BMP, TIFF or WebP file, read and checked without decoding.

The companion of :mod:`shared.image_header` (same rules, same :class:`ImageHeader`) for
the other formats OpenCV reads that camera images come in: PGM (machine-vision cameras,
datasets), BMP (Windows tools), TIFF (camera SDKs, microscopes), WebP. Only files the
user names on the command line are read in these formats
(:data:`shared.image_decode.FILE_FORMATS`); images from a peer or a memory stay PNG or
JPEG (:data:`shared.image_decode.WIRE_FORMATS`). OpenCV's rarer formats (JPEG 2000,
AVIF, OpenEXR, Radiance HDR, PFM, PAM, Sun raster) are refused by their first bytes.

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
3. TIFF (TIFF 6.0, sec. 2): ``II*\\0`` or ``MM\\0*``, the first IFD's offset, then
   its entries (tag, type, count, value or offset); every value that does not fit in
   its entry must lie in the file. The first IFD (the picture OpenCV reads) must give
   ImageWidth and ImageLength; BitsPerSample and SamplesPerPixel default to 1. BigTIFF
   is refused. Compressed strips are held to the pixel budget.
4. WebP (Google's WebP container specification): ``RIFF``, its size (within the file),
   ``WEBP``, then a ``VP8 `` (lossy: start code ``9D 01 2A``, 14-bit width and
   height), ``VP8L`` (lossless: signature ``2F``, 14-bit width - 1 and height - 1) or
   ``VP8X`` (extended: 24-bit canvas width - 1 and height - 1) chunk.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

from shared.errors import InputError
from shared.image_header import ImageFormat, ImageHeader

NETPBM_MAGICS = (b"P1", b"P2", b"P3", b"P4", b"P5", b"P6")
BMP_MAGIC = b"BM"
TIFF_MAGICS = (b"II*\x00", b"MM\x00*")
WEBP_MAGIC = b"RIFF"
#: The first bytes of every format read here.
MAGICS = (*NETPBM_MAGICS, BMP_MAGIC, *TIFF_MAGICS, WEBP_MAGIC)

#: Longest Netpbm header read (comments included), bytes.
MAX_NETPBM_HEADER_BYTES = 4096
#: One Netpbm header field: whitespace and comments, then at most 10 digits.
_NETPBM_FIELD = re.compile(rb"(?:[ \t\r\n\v\f]|#[^\r\n]*)+(\d{1,10})(?!\d)")
_BMP_DIB_SIZES = (12, 40, 52, 56, 108, 124)
#: compression -> bits per pixel it allows (BI_RGB, BI_RLE8, BI_RLE4, BI_BITFIELDS).
_BMP_COMPRESSIONS = {0: (1, 4, 8, 16, 24, 32), 1: (8,), 2: (4,), 3: (16, 32)}
#: Entries a TIFF IFD may have (a camera writes a few dozen).
MAX_TIFF_ENTRIES = 1024
#: TIFF field type -> bytes per value (TIFF 6.0, sec. 2, "Types"; 13 is IFD, TIFF-PM).
_TIFF_TYPE_BYTES = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 6: 1, 7: 1, 8: 2, 9: 4, 10: 8, 11: 4, 12: 8,
                    13: 4}
_TIFF_WIDTH, _TIFF_LENGTH, _TIFF_BITS, _TIFF_SAMPLES = 256, 257, 258, 277


def read_file_image_header(data: bytes, where: str | Path,
                           error: type[InputError] = InputError) -> ImageHeader:
    """Walk the header of the Netpbm, BMP, TIFF or WebP file ``data`` (module docstring).

    Args:
        data: the whole file, starting with one of :data:`MAGICS`.
        where: the file the bytes came from, for errors.
        error: the :class:`InputError` subclass to raise.

    Returns:
        The picture's header; the pixels are not looked at.

    Raises:
        InputError: (``error``) none of these formats, or a header that is malformed or
            declares more than the file holds; one line.
    """
    if data[:2] in NETPBM_MAGICS:
        return _netpbm_header(data, where, error)
    if data.startswith(BMP_MAGIC):
        return _bmp_header(data, where, error)
    if data.startswith(TIFF_MAGICS):
        return _tiff_header(data, where, error)
    if data.startswith(WEBP_MAGIC):
        return _webp_header(data, where, error)
    start = data[:8].hex(" ") if data else "nothing"
    raise error(where, f"not a Netpbm, BMP, TIFF or WebP image (the file starts with {start})")


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


def _tiff_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    def corrupt(problem: str) -> InputError:
        return error(where, f"corrupt TIFF: {problem}")

    order = "<" if data.startswith(b"II") else ">"
    if len(data) < 8:
        raise corrupt(f"{len(data)} bytes, shorter than its header")
    (ifd,) = struct.unpack_from(order + "I", data, 4)
    if ifd + 2 > len(data) or ifd < 8:
        raise corrupt(f"first IFD at byte {ifd} is outside bytes 8..{len(data) - 2}")
    (count,) = struct.unpack_from(order + "H", data, ifd)
    if count > MAX_TIFF_ENTRIES:
        raise corrupt(f"IFD at byte {ifd} declares {count} entries (at most "
                      f"{MAX_TIFF_ENTRIES})")
    if ifd + 2 + 12 * count > len(data):
        raise corrupt(f"IFD at byte {ifd} declares {count} entries, past the end of the file")
    fields: dict[int, int] = {}
    for k in range(count):
        at = ifd + 2 + 12 * k
        tag, kind, n = struct.unpack_from(order + "HHI", data, at)
        size = _TIFF_TYPE_BYTES.get(kind, 1) * n
        if size > 4:
            (offset,) = struct.unpack_from(order + "I", data, at + 8)
            if offset + size > len(data):
                raise corrupt(f"tag {tag} at byte {at} declares {size} bytes at byte {offset}, "
                              "past the end of the file")
            at = offset - 8  # its first value is read below from the offset
        if kind in (3, 4) and n >= 1:
            (fields[tag],) = struct.unpack_from(order + ("H" if kind == 3 else "I"), data, at + 8)
    width, height = fields.get(_TIFF_WIDTH, 0), fields.get(_TIFF_LENGTH, 0)
    if width < 1 or height < 1:
        raise corrupt(f"first IFD declares {width}x{height} px (ImageWidth, ImageLength)")
    return ImageHeader(ImageFormat.TIFF, width, height, fields.get(_TIFF_SAMPLES, 1),
                       fields.get(_TIFF_BITS, 1))


def _webp_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    def corrupt(problem: str) -> InputError:
        return error(where, f"corrupt WebP: {problem}")

    if len(data) < 30 or data[8:12] != b"WEBP":
        raise error(where, "not a WebP image (a RIFF file without a WEBP header)")
    (riff_size,) = struct.unpack_from("<I", data, 4)
    if riff_size + 8 > len(data):
        raise corrupt(f"RIFF declares {riff_size + 8} bytes, the file has {len(data)}")
    chunk, body = data[12:16], data[20:]
    channels = 3
    if chunk == b"VP8 ":
        if body[3:6] != b"\x9d\x01\x2a":
            raise corrupt("VP8 frame without its start code 9D 01 2A")
        width, height = (v & 0x3FFF for v in struct.unpack_from("<HH", body, 6))
    elif chunk == b"VP8L":
        if body[0] != 0x2F:
            raise corrupt(f"VP8L signature {body[0]:02X}, expected 2F")
        (bits,) = struct.unpack_from("<I", body, 1)
        width, height = (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1
        channels = 4 if bits >> 28 & 1 else 3
    elif chunk == b"VP8X":
        width = int.from_bytes(body[4:7], "little") + 1
        height = int.from_bytes(body[7:10], "little") + 1
        channels = 4 if body[0] & 0x10 else 3
    else:
        raise corrupt(f"first chunk {chunk!r} is none of VP8, VP8L, VP8X")
    if width < 1 or height < 1:
        raise corrupt(f"declares {width}x{height} px")
    return ImageHeader(ImageFormat.WEBP, width, height, channels, 8)
