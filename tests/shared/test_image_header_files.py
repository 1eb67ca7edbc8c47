"""Tests of shared/image_header_files.py and of decoding a user's files in those formats."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import CalibrationError, InputError
from shared.image_decode import FILE_FORMATS, decode_grey
from shared.image_header import ImageFormat, ImageHeader
from shared.image_header_files import MAGICS, read_file_image_header
from tests.shared.test_image_header import mutated

GREY = np.random.default_rng(5).integers(0, 256, (48, 64), dtype=np.uint8)
COLOUR = np.random.default_rng(6).integers(0, 256, (48, 64, 3), dtype=np.uint8)


def encoded(suffix: str, image: np.ndarray, params: tuple[int, ...] = ()) -> bytes:
    ok, data = cv2.imencode(suffix, image, list(params))
    assert ok
    return data.tobytes()


def refused(data: bytes) -> str:
    with pytest.raises(InputError) as info:
        read_file_image_header(data, "view.pgm")
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
    (".tif", GREY, (), ImageHeader(ImageFormat.TIFF, 64, 48, 1, 8)),
    (".tif", COLOUR, (cv2.IMWRITE_TIFF_COMPRESSION, 1),
     ImageHeader(ImageFormat.TIFF, 64, 48, 3, 8)),
    (".tif", GREY.astype(np.uint16), (), ImageHeader(ImageFormat.TIFF, 64, 48, 1, 16)),
    (".webp", GREY, (), ImageHeader(ImageFormat.WEBP, 64, 48, 3, 8)),
    (".webp", COLOUR, (cv2.IMWRITE_WEBP_QUALITY, 80), ImageHeader(ImageFormat.WEBP, 64, 48, 3, 8)),
], ids=["P5", "P5-16bit", "P2", "P6", "P4", "bmp8", "bmp24", "tiff-lzw", "tiff-raw-colour",
        "tiff-16bit", "webp-lossless", "webp-lossy"])
def test_headers_of_opencvs_files(suffix: str, image: np.ndarray, params: tuple[int, ...],
                                  header: ImageHeader) -> None:
    data = encoded(suffix, image, params)
    assert read_file_image_header(data, "view") == header
    decoded = decode_grey(data, "view", formats=FILE_FORMATS)
    assert np.array_equal(decoded, cv2.imdecode(np.frombuffer(data, np.uint8),
                                                cv2.IMREAD_GRAYSCALE))


def test_netpbm_comments_are_skipped() -> None:
    data = b"P5\n# made by hand\n4 # width\n2\n255\n" + bytes(range(8))
    assert read_file_image_header(data, "x") == ImageHeader(ImageFormat.NETPBM, 4, 2, 1, 8)


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


def test_broken_tiff() -> None:
    data = encoded(".tif", GREY)
    assert "first IFD at byte" in refused(data[:4] + b"\xff\xff\x00\x00" + data[8:])
    ifd = int.from_bytes(data[4:8], "little")
    assert "entries, past the end of the file" in refused(data[:ifd + 14])
    many = data[:ifd] + (5000).to_bytes(2, "little") + data[ifd + 2:]
    assert "declares 5000 entries (at most 1024)" in refused(many)
    assert "shorter than its header" in refused(b"II*\x00")


def test_broken_webp() -> None:
    data = encoded(".webp", COLOUR, (cv2.IMWRITE_WEBP_QUALITY, 80))
    assert "RIFF declares" in refused(data[:-10])
    assert "start code" in refused(data[:23] + b"\x00" + data[24:])
    assert "first chunk b'ABCD'" in refused(data[:12] + b"ABCD" + data[16:])
    assert "without a WEBP header" in refused(b"RIFF" + bytes(40))


def test_other_formats_and_wire_callers() -> None:
    assert "not a Netpbm, BMP, TIFF or WebP image" in refused(b"GIF89a")
    pgm = encoded(".pgm", GREY)
    # A peer or a memory never gets past PNG and JPEG.
    with pytest.raises(InputError, match="not a PNG or JPEG image"):
        decode_grey(pgm, "photo")
    with pytest.raises(CalibrationError, match=r"x\.jp2: not an image of a format read here "
                                               r"\(PNG, JPEG, Netpbm, BMP, TIFF, WebP; the file "
                                               r"starts with"):
        decode_grey(encoded(".jp2", GREY), "x.jp2", error=CalibrationError, formats=FILE_FORMATS)


SEEDS = [encoded(".pgm", GREY[:8, :8]), encoded(".pgm", GREY[:4, :4], (cv2.IMWRITE_PXM_BINARY, 0)),
         encoded(".pbm", GREY[:8, :8]), encoded(".bmp", COLOUR[:8, :8]),
         encoded(".bmp", GREY[:8, :8]), encoded(".tif", GREY[:8, :8]),
         encoded(".webp", GREY[:8, :8]), encoded(".webp", COLOUR[:16, :16],
                                                 (cv2.IMWRITE_WEBP_QUALITY, 80))]


@settings(derandomize=True, max_examples=400, deadline=None)
@given(st.sampled_from(SEEDS),
       st.lists(st.tuples(st.integers(0, 1 << 16), st.integers(0, 255)), max_size=8),
       st.integers(0, 1 << 16))
def test_fuzz_mutated_files_give_a_header_or_an_input_error(
        seed: bytes, flips: list[tuple[int, int]], cut: int) -> None:
    data = mutated(seed, flips, cut)
    try:
        header = read_file_image_header(data, "fuzz")
    except InputError as e:
        assert "\n" not in str(e)
    else:
        assert header.width_px >= 1 and header.height_px >= 1


@settings(derandomize=True, max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_random_bytes_after_a_magic(tail: bytes) -> None:
    for start in MAGICS:
        try:
            header = read_file_image_header(start + tail, "fuzz")
        except InputError as e:
            assert "\n" not in str(e)
        else:
            assert header.width_px >= 1 and header.height_px >= 1
