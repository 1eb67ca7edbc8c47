"""The header of a PNG or JPEG file, read and checked without decoding a pixel.

Theory of operation
-------------------

An image file says how big it is before it says anything else, and a decoder believes
it: OpenCV allocates the whole picture (and, for a chunk, the whole chunk) from what the
header declares, before the data shows whether the file can fill it. An 86-byte PNG can
so declare gigabytes. :func:`read_image_header` walks the file's structure instead,
checking every declared length against the bytes actually there, and returns the
picture's size for the caller to compare with its limits (:mod:`shared.image_decode`)
before any decoder runs.

Rules:

1. Only PNG and JPEG are read; anything else is refused by its first bytes.
2. PNG (ISO/IEC 15948, the W3C PNG specification, 2nd ed.): the 8-byte signature, then
   chunks of ``length (u32 BE) | type (4 ASCII letters) | data | CRC-32 (u32 BE)``;
   IHDR first (13 bytes: width, height, bit depth, colour type, compression, filter,
   interlace, section 11.2.2), at least one IDAT, IEND last. Every chunk's length must
   fit in the file, its CRC must match (section 5.3), and the compressed ancillary
   chunks (zTXt, iTXt, iCCP, which libpng inflates) may hold at most
   :data:`MAX_PNG_COMPRESSED_ANCILLARY_BYTES` in all.
3. JPEG (ITU-T T.81, annex B): SOI, then marker segments ``FF xx | length (u16 BE,
   counting itself) | data``; each length must fit in the file. One frame header
   (SOF0/1/2 Huffman or SOF9/10 arithmetic, DCT processes only; section B.2.2) gives
   precision, height, width and components; after each SOS, the entropy-coded data runs
   to the next marker (``FF`` followed by neither ``00`` stuffing nor RST0-7, B.1.1.5).
   Progressive files decode every scan over the whole picture, so at most
   :data:`MAX_JPEG_SCANS` scans are accepted.
4. At most :data:`MAX_SEGMENTS` chunks or marker segments: with the file's size capped
   by the caller, the walk takes milliseconds whatever the file.

The walk is linear in the file's size and allocates nothing in proportion to what the
file declares. Errors are one line: what is wrong, with the byte offset.
"""

from __future__ import annotations

import re
import struct
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

from shared.errors import InputError

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
JPEG_SOI = b"\xff\xd8"

#: Sum of the lengths of zTXt, iTXt and iCCP chunks a PNG may hold, bytes: libpng
#: inflates them (up to ~1032x), an ICC profile or a caption need a few KiB.
MAX_PNG_COMPRESSED_ANCILLARY_BYTES = 1 << 16
#: Scans a JPEG may hold: a progressive camera JPEG has about 10; each costs a pass
#: over the whole picture.
MAX_JPEG_SCANS = 64
#: Chunks (PNG) or marker segments (JPEG) a file may hold: encoders write a few dozen,
#: or one IDAT per 8 KiB; the cap keeps the walk's Python loop short on any file.
MAX_SEGMENTS = 1 << 14

_PNG_MAX_LENGTH = (1 << 31) - 1  # section 5.3: a chunk length is at most 2^31 - 1
_PNG_COMPRESSED_ANCILLARY = frozenset({b"zTXt", b"iTXt", b"iCCP"})
#: PNG colour type -> (channels, allowed bit depths), section 11.2.2 table 11.1.
_PNG_COLOUR_TYPES = {
    0: (1, (1, 2, 4, 8, 16)),  # greyscale
    2: (3, (8, 16)),  # truecolour
    3: (3, (1, 2, 4, 8)),  # indexed: palette entries are RGB
    4: (2, (8, 16)),  # greyscale with alpha
    6: (4, (8, 16)),  # truecolour with alpha
}
_JPEG_SOF = frozenset({0xC0, 0xC1, 0xC2, 0xC9, 0xCA})  # DCT, sequential or progressive
_JPEG_OTHER_SOF = frozenset({0xC3, 0xC5, 0xC6, 0xC7, 0xCB, 0xCD, 0xCE, 0xCF})
_JPEG_SOS, _JPEG_EOI, _JPEG_SOI = 0xDA, 0xD9, 0xD8
_JPEG_STANDALONE = frozenset({0x01, *range(0xD0, 0xD8)})  # TEM, RST0-7: no length
#: A marker's FF and the fill bytes (more FF, B.1.1.2) before its code.
_JPEG_FILL = re.compile(rb"\xff+(?=[^\xff])")
#: The start of the next marker after entropy-coded data: FF not followed by a stuffed
#: 00, a restart marker or another FF (fill).
_JPEG_NEXT_MARKER = re.compile(rb"\xff(?=[^\x00\xd0-\xd7\xff])")

#: Makes the error for a problem found in the file (its text after "corrupt PNG: ").
_Corrupt = Callable[[str], InputError]


class ImageFormat(Enum):
    """The formats whose header is walked: PNG and JPEG here (:func:`read_image_header`),
    the others in :mod:`shared.image_header_files` (a user's own files only)."""

    PNG = "PNG"
    JPEG = "JPEG"
    NETPBM = "Netpbm"
    BMP = "BMP"
    TIFF = "TIFF"
    WEBP = "WebP"


@dataclass(frozen=True, slots=True)
class ImageHeader:
    """What an image file declares about its picture.

    Attributes:
        format: the file's format.
        width_px: picture width, px (>= 1).
        height_px: picture height, px (>= 1).
        channels: samples per pixel as stored: PNG 1 grey, 2 grey + alpha, 3 colour or
            palette, 4 colour + alpha; JPEG the frame's components (1-4); Netpbm 1
            (PBM, PGM) or 3 (PPM); BMP 3, or 4 with 32 bits per pixel; TIFF
            SamplesPerPixel; WebP 3, or 4 with alpha.
        bit_depth: bits per sample (PNG 1-16; JPEG precision 8 or 12; Netpbm 1, 8 or
            16; BMP bits per pixel, 1-32; TIFF the first BitsPerSample; WebP 8).
    """

    format: ImageFormat
    width_px: int
    height_px: int
    channels: int
    bit_depth: int

    @property
    def pixels(self) -> int:
        """``width_px * height_px``."""
        return self.width_px * self.height_px


def read_image_header(data: bytes, where: str | Path,
                      error: type[InputError] = InputError) -> ImageHeader:
    """Walk the structure of the PNG or JPEG file ``data`` (module docstring).

    Args:
        data: the whole file.
        where: the file (or message) the bytes came from, for errors.
        error: the :class:`InputError` subclass to raise (a memory's loader raises
            :class:`shared.errors.MemoryFormatError`).

    Returns:
        The picture's header; the pixels are not looked at.

    Raises:
        InputError: (``error``) not a PNG or JPEG file, or one whose structure is
            broken (a length past the end of the file, a bad CRC, a missing or
            second header, too many scans...), naming the byte offset.
    """
    if data.startswith(PNG_SIGNATURE):
        return _png_header(data, where, error)
    if data.startswith(JPEG_SOI):
        return _jpeg_header(data, where, error)
    start = data[:8].hex(" ") if data else "nothing"
    raise error(where, f"not a PNG or JPEG image (the file starts with {start})")


def _png_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    def corrupt(problem: str) -> InputError:
        return error(where, f"corrupt PNG: {problem}")

    header: ImageHeader | None = None
    idat_seen = False
    compressed_ancillary = 0
    view = memoryview(data)
    pos = len(PNG_SIGNATURE)
    chunks = 0
    while True:
        chunks += 1
        if chunks > MAX_SEGMENTS:
            raise corrupt(f"more than {MAX_SEGMENTS} chunks (at byte {pos})")
        if pos + 12 > len(data):
            raise corrupt(f"cut short at byte {pos} (no IEND chunk)")
        length, kind = struct.unpack_from(">I4s", data, pos)
        name = kind.decode("latin-1")
        if not kind.isalpha() or not kind.isascii():
            raise corrupt(f"chunk type {kind!r} at byte {pos} is not 4 ASCII letters")
        if length > _PNG_MAX_LENGTH or pos + 12 + length > len(data):
            raise corrupt(f"chunk {name} at byte {pos} declares {length} bytes, the file "
                          f"has {len(data) - pos - 12} after its header")
        body = view[pos + 8:pos + 8 + length]  # no copy, however long the chunk
        (crc,) = struct.unpack_from(">I", data, pos + 8 + length)
        if zlib.crc32(body, zlib.crc32(kind)) != crc:
            raise corrupt(f"chunk {name} at byte {pos}: CRC mismatch")
        if header is None:
            if kind != b"IHDR":
                raise corrupt(f"the first chunk is {name}, not IHDR")
            header = _png_ihdr(body, corrupt)
        elif kind == b"IHDR":
            raise corrupt(f"a second IHDR chunk at byte {pos}")
        elif kind == b"IDAT":
            idat_seen = True
        elif kind == b"IEND":
            if not idat_seen:
                raise corrupt("no IDAT chunk before IEND")
            return header
        elif kind in _PNG_COMPRESSED_ANCILLARY:
            compressed_ancillary += length
            if compressed_ancillary > MAX_PNG_COMPRESSED_ANCILLARY_BYTES:
                raise corrupt(f"compressed ancillary chunks (zTXt, iTXt, iCCP) exceed "
                              f"{MAX_PNG_COMPRESSED_ANCILLARY_BYTES} bytes at the {name} "
                              f"chunk at byte {pos}")
        pos += 12 + length


def _png_ihdr(body: memoryview, corrupt: _Corrupt) -> ImageHeader:
    """The IHDR chunk's 13 bytes as a header (section 11.2.2)."""
    if len(body) != 13:
        raise corrupt(f"IHDR holds {len(body)} bytes, not 13")
    width, height, depth, colour, compression, filtering, interlace = struct.unpack(
        ">IIBBBBB", body)
    if not 1 <= width <= _PNG_MAX_LENGTH or not 1 <= height <= _PNG_MAX_LENGTH:
        raise corrupt(f"IHDR declares {width}x{height} px (each side must be 1..2^31-1)")
    if colour not in _PNG_COLOUR_TYPES:
        raise corrupt(f"IHDR colour type {colour} (one of 0, 2, 3, 4, 6)")
    channels, depths = _PNG_COLOUR_TYPES[colour]
    if depth not in depths:
        raise corrupt(f"IHDR bit depth {depth} with colour type {colour} (one of {depths})")
    if compression != 0 or filtering != 0 or interlace not in (0, 1):
        raise corrupt(f"IHDR compression {compression}, filter {filtering}, interlace "
                      f"{interlace} (0, 0 and 0 or 1)")
    return ImageHeader(ImageFormat.PNG, width, height, channels, depth)


def _jpeg_header(data: bytes, where: str | Path, error: type[InputError]) -> ImageHeader:
    def corrupt(problem: str) -> InputError:
        return error(where, f"corrupt JPEG: {problem}")

    header: ImageHeader | None = None
    scans = 0
    pos = len(JPEG_SOI)
    segments = 0
    while pos < len(data):
        if data[pos] != 0xFF:
            raise corrupt(f"byte {pos} is 0x{data[pos]:02x}, not a marker")
        segments += 1
        if segments > MAX_SEGMENTS:
            raise corrupt(f"more than {MAX_SEGMENTS} marker segments (at byte {pos})")
        fill = _JPEG_FILL.match(data, pos)
        if fill is None:  # only fill bytes to the end of the file
            break
        pos = fill.end() - 1
        marker = data[pos + 1]
        if marker == _JPEG_EOI:
            break
        if marker in _JPEG_STANDALONE:
            pos += 2
            continue
        if marker == _JPEG_SOI:
            raise corrupt(f"a second SOI marker at byte {pos}")
        if pos + 4 > len(data):
            raise corrupt(f"marker FF{marker:02X} at byte {pos} cut short")
        (length,) = struct.unpack_from(">H", data, pos + 2)
        if length < 2 or pos + 2 + length > len(data):
            raise corrupt(f"segment FF{marker:02X} at byte {pos} declares {length} bytes, "
                          f"the file has {len(data) - pos - 2} after its marker")
        body = data[pos + 4:pos + 2 + length]
        end = pos + 2 + length
        if marker in _JPEG_SOF:
            if header is not None:
                raise corrupt(f"a second frame header (FF{marker:02X}) at byte {pos}")
            header = _jpeg_frame(body, pos, corrupt)
        elif marker in _JPEG_OTHER_SOF:
            raise corrupt(f"frame type FF{marker:02X} at byte {pos} (lossless or "
                          f"hierarchical) is not read; DCT JPEGs only")
        elif marker == _JPEG_SOS:
            if header is None:
                raise corrupt(f"a scan (SOS) at byte {pos} before the frame header")
            scans += 1
            if scans > MAX_JPEG_SCANS:
                raise corrupt(f"more than {MAX_JPEG_SCANS} scans (scan at byte {pos})")
            found = _JPEG_NEXT_MARKER.search(data, end)
            end = len(data) if found is None else found.start()
        pos = end
    if header is None:
        raise corrupt("no frame header (SOF0, SOF1, SOF2, SOF9 or SOF10)")
    if scans == 0:
        raise corrupt("no scan (SOS)")
    return header


def _jpeg_frame(body: bytes, pos: int, corrupt: _Corrupt) -> ImageHeader:
    """The frame header's body (B.2.2: P, Y, X, Nf, then 3 bytes per component)."""
    if len(body) < 6:
        raise corrupt(f"frame header at byte {pos} holds {len(body)} bytes")
    precision, height, width, components = struct.unpack_from(">BHHB", body)
    if len(body) != 6 + 3 * components:
        raise corrupt(f"frame header at byte {pos} holds {len(body)} bytes for "
                      f"{components} components")
    if precision not in (8, 12):
        raise corrupt(f"frame header at byte {pos}: precision {precision} bits (8 or 12)")
    if not 1 <= components <= 4:
        raise corrupt(f"frame header at byte {pos}: {components} components (1 to 4)")
    if width == 0 or height == 0:
        raise corrupt(f"frame header at byte {pos} declares {width}x{height} px")
    for i in range(components):
        sampling = body[6 + 3 * i + 1]
        if not (1 <= sampling >> 4 <= 4 and 1 <= sampling & 0x0F <= 4):
            raise corrupt(f"frame header at byte {pos}: component {i} sampling factors "
                          f"0x{sampling:02x} (each 1 to 4)")
    return ImageHeader(ImageFormat.JPEG, width, height, components, precision)
