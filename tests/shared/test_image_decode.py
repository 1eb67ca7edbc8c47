"""decode_grey / read_grey: real photos decode as before; bombs are refused from their
header with one line, before OpenCV sees them."""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared import image_decode
from shared.errors import InputError
from shared.image_decode import (
    MAX_PIXELS,
    MAX_SIDE_PX,
    check_image,
    decode_grey,
    photo_pixel_limit,
    read_grey,
)
from tools.bench.hostile_images import bogus_chunk_png, header_bomb_png, large_png

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"
RNG_IMAGE = np.random.default_rng(3).integers(0, 256, (60, 80, 3), dtype=np.uint8)


def one_line(error: pytest.ExceptionInfo[InputError]) -> str:
    message = str(error.value)
    assert "\n" not in message
    return message


@pytest.mark.skipif(not REALDATA.is_dir(), reason="needs ../shared/realdata")
@pytest.mark.parametrize("name", ["fisheye_pair/left_fisheye_img_0.png",
                                  "catadioptric/1.jpg"])
def test_a_real_photo_decodes_as_opencv_reads_it(name: str) -> None:
    path = REALDATA / name
    image = read_grey(path, photo_pixel_limit(1280, 960))
    assert image.dtype == np.uint8 and image.ndim == 2
    assert np.array_equal(image, cv2.imread(str(path), cv2.IMREAD_GRAYSCALE))


@pytest.mark.parametrize(("bomb", "fragment"), [
    (header_bomb_png, "PNG of 32768x32768 px: 1073741824 pixels, more than the 1920000"),
    (lambda: bogus_chunk_png(np.random.default_rng(0)),
     "corrupt PNG: chunk tEXt at byte 33 declares 2147483647 bytes"),
    (large_png, "PNG of 30000x30000 px: 900000000 pixels, more than the 1920000"),
], ids=["header_bomb", "bogus_chunk", "large_png"])
def test_the_issues_bombs_are_refused_in_one_line(
        bomb: Callable[[], bytes], fragment: str, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "3.png"
    path.write_bytes(bomb())
    # OpenCV must not even be asked: the refusal comes from the header.
    monkeypatch.setattr(cv2, "imdecode", lambda *_: pytest.fail("decoded a bomb"))
    with pytest.raises(InputError) as caught:
        read_grey(path, photo_pixel_limit(800, 600))
    message = one_line(caught)
    assert message.startswith(f"{path}: ") and fragment in message


def test_the_absolute_limits_hold_whatever_the_budget() -> None:
    with pytest.raises(InputError, match=f"a side is longer than {MAX_SIDE_PX} px"):
        check_image(header_bomb_png(MAX_SIDE_PX + 1), "x.png", max_pixels=1 << 40)
    with pytest.raises(InputError, match=f"more than the {MAX_PIXELS} allowed"):
        check_image(large_png(8192), "x.png", max_pixels=1 << 40)
    assert check_image(large_png(4096), "x.png").pixels == 4096 * 4096


def test_photo_budget_is_a_few_camera_images() -> None:
    assert photo_pixel_limit(800, 600) == 4 * 800 * 600
    assert photo_pixel_limit(20000, 20000) == MAX_PIXELS


def test_a_file_over_the_size_cap_is_not_read_whole(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(image_decode, "MAX_FILE_BYTES", 1000)
    path = tmp_path / "big.png"
    path.write_bytes(cv2.imencode(".png", RNG_IMAGE)[1].tobytes())
    with pytest.raises(InputError) as caught:
        read_grey(path)
    assert one_line(caught) == f"{path}: 1001 bytes, more than the 1000 an image file may have"


def test_an_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(InputError) as caught:
        read_grey(tmp_path / "none.jpg")
    assert one_line(caught) == f"{tmp_path / 'none.jpg'}: cannot read the image: " \
                               "No such file or directory"


def test_pixel_data_that_does_not_decode() -> None:
    data = cv2.imencode(".png", RNG_IMAGE)[1].tobytes()
    # A well-formed chunk structure around an IDAT that is not a zlib stream.
    idat = data.index(b"IDAT") - 4
    length = struct.unpack_from(">I", data, idat)[0]
    junk = bytes(length)
    crc = struct.pack(">I", zlib.crc32(b"IDAT" + junk))
    broken = data[:idat + 8] + junk + crc + data[idat + 12 + length:]
    with pytest.raises(InputError, match="corrupt PNG: "):
        decode_grey(broken, "x.png")


def test_a_jpeg_turned_by_its_exif_orientation_is_accepted() -> None:
    image = RNG_IMAGE[:, :, 0]
    data = cv2.imencode(".jpg", image)[1].tobytes()
    # APP1 Exif, big-endian TIFF, one IFD entry: Orientation (0x0112) SHORT = 6 (90 deg CW).
    tiff = b"MM\x00\x2a\x00\x00\x00\x08" + b"\x00\x01" + struct.pack(
        ">HHIHH", 0x0112, 3, 1, 6, 0) + b"\x00\x00\x00\x00"
    app1 = b"Exif\x00\x00" + tiff
    turned = data[:2] + b"\xff\xe1" + struct.pack(">H", 2 + len(app1)) + app1 + data[2:]
    decoded = decode_grey(turned, "x.jpg")
    assert decoded.shape == (80, 60)
    assert np.array_equal(decoded, cv2.imdecode(np.frombuffer(turned, np.uint8),
                                                cv2.IMREAD_GRAYSCALE))


SEEDS = [cv2.imencode(".png", RNG_IMAGE[:16, :16])[1].tobytes(),
         cv2.imencode(".jpg", RNG_IMAGE[:16, :16])[1].tobytes(),
         cv2.imencode(".jpg", RNG_IMAGE[:16, :16, 0],
                      [cv2.IMWRITE_JPEG_PROGRESSIVE, 1])[1].tobytes()]


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.sampled_from(SEEDS),
       st.lists(st.tuples(st.integers(0, 1 << 12), st.integers(0, 255)), min_size=1,
                max_size=6))
def test_fuzz_decode_gives_a_grey_image_or_an_input_error(
        seed: bytes, flips: list[tuple[int, int]]) -> None:
    data = bytearray(seed)
    for at, value in flips:
        data[at % len(data)] = value
    try:
        image = decode_grey(bytes(data), "fuzz", max_pixels=1 << 16)
    except InputError as e:
        assert "\n" not in str(e)
    else:
        assert image.dtype == np.uint8 and image.ndim == 2 and image.size <= 1 << 16
