"""read_image_header: PNG chunks and JPEG segments walked without decoding, every
declared length checked against the file."""

from __future__ import annotations

import struct

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.errors import InputError, MemoryFormatError
from shared.image_header import (
    MAX_JPEG_SCANS,
    MAX_PNG_COMPRESSED_ANCILLARY_BYTES,
    MAX_SEGMENTS,
    PNG_SIGNATURE,
    ImageFormat,
    ImageHeader,
    read_image_header,
)
from tools.bench.hostile_images import bogus_chunk_png, header_bomb_png, large_png, png_chunk

RNG_IMAGE = np.random.default_rng(7).integers(0, 256, (48, 64, 3), dtype=np.uint8)


def png(image: np.ndarray) -> bytes:
    return cv2.imencode(".png", image)[1].tobytes()


def jpeg(image: np.ndarray, progressive: bool = False) -> bytes:
    params = [cv2.IMWRITE_JPEG_QUALITY, 90, cv2.IMWRITE_JPEG_PROGRESSIVE, int(progressive)]
    return cv2.imencode(".jpg", image, params)[1].tobytes()


def chunks(data: bytes) -> list[tuple[int, bytes]]:
    """(offset, type) of each chunk of a well-formed PNG."""
    out, pos = [], len(PNG_SIGNATURE)
    while pos < len(data):
        length, kind = struct.unpack_from(">I4s", data, pos)
        out.append((pos, kind))
        pos += 12 + length
    return out


def with_chunk_after_ihdr(data: bytes, chunk: bytes) -> bytes:
    after_ihdr = len(PNG_SIGNATURE) + 25
    return data[:after_ihdr] + chunk + data[after_ihdr:]


def refused(data: bytes) -> str:
    with pytest.raises(InputError) as caught:
        read_image_header(data, "photo.png")
    message = str(caught.value)
    assert "\n" not in message and message.startswith("photo.png: ")
    return message


class TestGoodFiles:
    @pytest.mark.parametrize(("image", "channels", "depth"), [
        (RNG_IMAGE[:, :, 0], 1, 8),
        (RNG_IMAGE, 3, 8),
        (np.dstack([RNG_IMAGE, RNG_IMAGE[:, :, :1]]), 4, 8),
        (RNG_IMAGE[:, :, 0].astype(np.uint16) * 257, 1, 16),
    ], ids=["grey", "colour", "colour+alpha", "grey16"])
    def test_png(self, image: np.ndarray, channels: int, depth: int) -> None:
        assert read_image_header(png(image), "x.png") == ImageHeader(
            ImageFormat.PNG, 64, 48, channels, depth)

    @pytest.mark.parametrize("progressive", [False, True])
    @pytest.mark.parametrize(("image", "components"), [(RNG_IMAGE[:, :, 0], 1), (RNG_IMAGE, 3)])
    def test_jpeg(self, image: np.ndarray, components: int, progressive: bool) -> None:
        header = read_image_header(jpeg(image, progressive), "x.jpg")
        assert header == ImageHeader(ImageFormat.JPEG, 64, 48, components, 8)
        assert header.pixels == 64 * 48

    def test_a_jpeg_cut_short_in_its_scan_still_has_a_header(self) -> None:
        # Decoders read a truncated baseline JPEG (the bottom grey): so does the walk.
        data = jpeg(RNG_IMAGE)
        assert read_image_header(data[:len(data) * 2 // 3], "x.jpg").width_px == 64

    def test_the_bombs_declare_what_they_declare(self) -> None:
        # The walk only reads structure: sizes are for the caller to judge.
        assert read_image_header(header_bomb_png(), "x.png").pixels == 1 << 30
        assert read_image_header(large_png(3000), "x.png").width_px == 3000


class TestBrokenPng:
    def test_a_chunk_length_past_the_end_of_the_file(self) -> None:
        message = refused(bogus_chunk_png(np.random.default_rng(0)))
        assert "corrupt PNG: chunk tEXt at byte 33 declares 2147483647 bytes" in message

    def test_a_bad_crc(self) -> None:
        data = bytearray(png(RNG_IMAGE))
        data[-20] ^= 0xFF  # in the last IDAT chunk's data
        pos = [p for p, kind in chunks(bytes(data)) if kind == b"IDAT"][-1]
        assert refused(bytes(data)).endswith(f"corrupt PNG: chunk IDAT at byte {pos}: "
                                             "CRC mismatch")

    def test_no_iend(self) -> None:
        assert refused(png(RNG_IMAGE)[:-12]).endswith("(no IEND chunk)")

    def test_ihdr_not_first_or_twice(self) -> None:
        data = png(RNG_IMAGE)
        ihdr = data[8:33]
        assert "the first chunk is tEXt" in refused(
            PNG_SIGNATURE + png_chunk(b"tEXt", b"a\x00b") + data[8:])
        assert "a second IHDR chunk at byte 33" in refused(with_chunk_after_ihdr(data, ihdr))

    def test_no_idat(self) -> None:
        data = png(RNG_IMAGE)
        assert "no IDAT chunk before IEND" in refused(data[:33] + data[-12:])

    @pytest.mark.parametrize(("fields", "fragment"), [
        ((0, 10, 8, 0, 0, 0, 0), "declares 0x10 px"),
        ((10, 10, 8, 5, 0, 0, 0), "colour type 5"),
        ((10, 10, 16, 3, 0, 0, 0), "bit depth 16 with colour type 3"),
        ((10, 10, 8, 0, 1, 0, 0), "compression 1"),
        ((10, 10, 8, 0, 0, 0, 2), "interlace 2"),
    ])
    def test_a_bad_ihdr(self, fields: tuple[int, ...], fragment: str) -> None:
        data = png(RNG_IMAGE)
        ihdr = png_chunk(b"IHDR", struct.pack(">IIBBBBB", *fields))
        assert fragment in refused(data[:8] + ihdr + data[33:])

    def test_compressed_ancillary_chunks_are_capped(self) -> None:
        data = png(RNG_IMAGE)
        small = png_chunk(b"zTXt", b"k\x00\x00" + bytes(1000))
        assert read_image_header(with_chunk_after_ihdr(data, small), "x.png").width_px == 64
        big = png_chunk(b"iCCP", b"p\x00\x00" + bytes(MAX_PNG_COMPRESSED_ANCILLARY_BYTES))
        assert "compressed ancillary chunks (zTXt, iTXt, iCCP) exceed" in refused(
            with_chunk_after_ihdr(data, big))

    def test_a_chunk_type_that_is_not_letters(self) -> None:
        data = png(RNG_IMAGE)
        assert "is not 4 ASCII letters" in refused(
            with_chunk_after_ihdr(data, png_chunk(b"t\x00Xt", b"")))


class TestBrokenJpeg:
    def test_a_segment_length_past_the_end_of_the_file(self) -> None:
        data = jpeg(RNG_IMAGE)
        lying = data[:2] + b"\xff\xfe\xff\xf0" + b"comment"  # a COM segment of 65520 bytes
        assert "corrupt JPEG: segment FFFE at byte 2 declares 65520 bytes" in refused(lying)

    def test_no_frame_header_or_scan(self) -> None:
        data = jpeg(RNG_IMAGE)
        sof = data.index(b"\xff\xc0")
        assert "no frame header" in refused(data[:sof] + b"\xff\xd9")
        sos = data.index(b"\xff\xda")
        assert "no scan (SOS)" in refused(data[:sos] + b"\xff\xd9")

    def test_a_scan_before_the_frame_header(self) -> None:
        data = jpeg(RNG_IMAGE)
        sof, sos = data.index(b"\xff\xc0"), data.index(b"\xff\xda")
        length = struct.unpack_from(">H", data, sof + 2)[0]
        frame = data[sof:sof + 2 + length]
        moved = data[:sof] + data[sof + 2 + length:sos] + data[sos:-2] + frame + b"\xff\xd9"
        assert "a scan (SOS) at byte" in refused(moved)

    def test_scans_are_capped(self) -> None:
        data = jpeg(RNG_IMAGE, progressive=True)
        sos = data.index(b"\xff\xda")
        scan = data[sos:-2]  # every scan, to EOI: their count over the cap
        copies = MAX_JPEG_SCANS // data.count(b"\xff\xda") + 1
        assert f"more than {MAX_JPEG_SCANS} scans" in refused(
            data[:sos] + scan * copies + b"\xff\xd9")

    def test_lossless_and_hierarchical_frames_are_refused(self) -> None:
        data = jpeg(RNG_IMAGE)
        sof = data.index(b"\xff\xc0")
        assert "frame type FFC3" in refused(data[:sof + 1] + b"\xc3" + data[sof + 2:])

    def test_a_bad_frame_header(self) -> None:
        data = jpeg(RNG_IMAGE)
        sof = data.index(b"\xff\xc0")
        zero_width = data[:sof + 7] + b"\x00\x00" + data[sof + 9:]
        assert "declares 0x48 px" in refused(zero_width)


def test_other_formats_are_refused_by_their_first_bytes() -> None:
    bmp = cv2.imencode(".bmp", RNG_IMAGE)[1].tobytes()
    assert refused(bmp) == "photo.png: not a PNG or JPEG image (the file starts with 42 4d " \
                           f"{' '.join(f'{b:02x}' for b in bmp[2:8])})"
    assert refused(b"").endswith("(the file starts with nothing)")


def test_the_error_class_is_the_callers() -> None:
    with pytest.raises(MemoryFormatError, match="corrupt PNG"):
        read_image_header(png(RNG_IMAGE)[:-12], "mem/images/3.png", MemoryFormatError)


SEEDS = [png(RNG_IMAGE[:8, :8, 0]), png(RNG_IMAGE[:8, :8]), jpeg(RNG_IMAGE[:16, :16, 0]),
         jpeg(RNG_IMAGE[:16, :16], progressive=True)]


def mutated(seed: bytes, flips: list[tuple[int, int]], cut: int) -> bytes:
    """``seed`` with the bytes at ``flips`` (position modulo the length, value) replaced,
    then cut short by ``cut`` modulo its length (at least one byte is kept)."""
    data = bytearray(seed)
    for at, value in flips:
        data[at % len(data)] = value
    return bytes(data[:max(1, len(data) - cut % len(data))])


@settings(derandomize=True, max_examples=300, deadline=None)
@given(st.sampled_from(SEEDS),
       st.lists(st.tuples(st.integers(0, 1 << 16), st.integers(0, 255)), max_size=8),
       st.integers(0, 1 << 16))
def test_fuzz_mutated_files_give_a_header_or_an_input_error(
        seed: bytes, flips: list[tuple[int, int]], cut: int) -> None:
    data = mutated(seed, flips, cut)
    try:
        header = read_image_header(data, "fuzz")
    except InputError as e:
        assert "\n" not in str(e)
    else:
        assert header.width_px >= 1 and header.height_px >= 1
        assert 1 <= header.channels <= 4


@settings(derandomize=True, max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_fuzz_random_bytes_after_a_signature(tail: bytes) -> None:
    for start in (PNG_SIGNATURE, b"\xff\xd8"):
        try:
            header = read_image_header(start + tail, "fuzz")
        except InputError as e:
            assert "\n" not in str(e)
        else:
            assert header.width_px >= 1 and header.height_px >= 1


def test_the_walk_is_short_on_any_file() -> None:
    # Many empty chunks, a run of fill bytes: refused or read at C speed, no long loop.
    data = png(RNG_IMAGE)
    many = png_chunk(b"tEXt", b"") * (MAX_SEGMENTS + 1)
    assert f"more than {MAX_SEGMENTS} chunks" in refused(with_chunk_after_ihdr(data, many))
    comments = b"\xff\xfe\x00\x02" * (MAX_SEGMENTS + 1)
    assert f"more than {MAX_SEGMENTS} marker segments" in refused(b"\xff\xd8" + comments)
    frame = jpeg(RNG_IMAGE)
    fill = frame[:2] + b"\xff" * (1 << 22) + frame[2:]
    assert read_image_header(fill, "x.jpg").width_px == 64
