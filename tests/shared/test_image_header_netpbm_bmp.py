"""Tests of shared/image_header_netpbm_bmp.py and of decoding local files in those formats."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from shared.errors import CalibrationError, InputError
from shared.image_decode import FILE_FORMATS, decode_grey
from shared.image_header import ImageFormat, ImageHeader
from shared.image_header_netpbm_bmp import read_netpbm_or_bmp_header

GREY = np.random.default_rng(5).integers(0, 256, (48, 64), dtype=np.uint8)
COLOUR = np.random.default_rng(6).integers(0, 256, (48, 64, 3), dtype=np.uint8)


def encoded(suffix: str, image: np.ndarray, params: tuple[int, ...] = ()) -> bytes:
    ok, data = cv2.imencode(suffix, image, list(params))
    assert ok
    return data.tobytes()


def refused(data: bytes) -> str:
    with pytest.raises(InputError) as info:
        read_netpbm_or_bmp_header(data, "view.pgm")
    message = str(info.value)
    assert message.startswith("view.pgm: ") and "\n" not in message
    return message


@pytest.mark.parametrize(("suffix", "image", "params", "header"), [
    (".pgm", GREY, (), ImageHeader(ImageFormat.NETPBM, 64, 48, 1, 8)),
    (".pgm", GREY.astype(np.uint16) * 257, (), ImageHeader(ImageFormat.NETPBM, 64, 48, 1, 16)),
    (".pgm", GREY, (cv2.IMWRITE_PXM_BINARY, 0), ImageHeader(ImageFormat.NETPBM, 64, 48, 1, 8)),
    (".ppm", COLOUR, (), ImageHeader(ImageFormat.NETPBM, 64, 48, 3, 8)),
    (".pbm", GREY, (), ImageHeader(ImageFormat.NETPBM, 64, 48, 1, 1)),
    (".bmp", GREY, (), ImageHeader(ImageFormat.BMP, 64, 48, 3, 8)),
    (".bmp", COLOUR, (), ImageHeader(ImageFormat.BMP, 64, 48, 3, 24)),
], ids=["P5", "P5-16bit", "P2", "P6", "P4", "bmp8", "bmp24"])
def test_headers_of_opencvs_files(suffix: str, image: np.ndarray, params: tuple[int, ...],
                                  header: ImageHeader) -> None:
    data = encoded(suffix, image, params)
    assert read_netpbm_or_bmp_header(data, "view") == header
    decoded = decode_grey(data, "view", formats=FILE_FORMATS)
    assert np.array_equal(decoded, cv2.imdecode(np.frombuffer(data, np.uint8),
                                                cv2.IMREAD_GRAYSCALE))


def test_netpbm_comments_are_skipped() -> None:
    data = b"P5\n# made by hand\n4 # width\n2\n255\n" + bytes(range(8))
    assert read_netpbm_or_bmp_header(data, "x") == ImageHeader(ImageFormat.NETPBM, 4, 2, 1, 8)


@pytest.mark.parametrize(("data", "problem"), [
    (b"P5\n64 48\n255\n" + bytes(100), "64x48 px need 3072 bytes of raster, the file has 100"),
    (b"P5\n64\n", "no height at byte 5"),
    (b"P5 0 48 255\n" + bytes(10), "declares 0x48 px"),
    (b"P5 4 2 70000\n" + bytes(16), "maxval 70000 is not in 1..65535"),
    (b"P5 4 2 255", "no whitespace before the raster"),
    (b"P5 12345678901 2 255\n", "no width at byte 2"),
])
def test_broken_netpbm(data: bytes, problem: str) -> None:
    assert problem in refused(data)


def test_broken_bmp() -> None:
    data = encoded(".bmp", COLOUR)
    assert "need 9216 bytes of pixel data" in refused(data[:-100])
    assert "DIB header of 99 bytes" in refused(data[:14] + b"\x63" + data[15:])
    assert "2 planes (must be 1)" in refused(data[:26] + b"\x02\x00" + data[28:])
    assert "pixel data offset" in refused(data[:10] + b"\xff\xff\xff\x00" + data[14:])
    assert "shorter than its headers" in refused(b"BM" + bytes(10))


def test_other_formats_and_wire_callers() -> None:
    assert "not a Netpbm or BMP image" in refused(b"GIF89a")
    pgm = encoded(".pgm", GREY)
    # A peer or a memory never gets past PNG and JPEG.
    with pytest.raises(InputError, match="not a PNG or JPEG image"):
        decode_grey(pgm, "photo")
    with pytest.raises(CalibrationError, match=r"x.tif: not an image of a format read here "
                                               r"\(PNG, JPEG, Netpbm, BMP; the file starts with"):
        decode_grey(encoded(".tif", GREY), "x.tif", error=CalibrationError, formats=FILE_FORMATS)
