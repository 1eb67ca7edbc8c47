"""Hostile photo goals (issue 15, item 3): the image bombs, and what they cost the robot.

:func:`measure` writes each bomb of the issue (and a valid photo) to a file and hands it,
in a fresh Python process, to the robot's real photo path
(:func:`robot.worker.find_photo`, as the worker runs it for a ``GOTO_PHOTO``), over a
memory whose one key image is the valid photo's scene. Per file it reports the child's
peak resident memory, the time ``find_photo`` took, and whether the photo was refused
(before decoding) or found in the memory.

The bombs are built here, also for the tests:

- :func:`header_bomb_png`: 69 bytes declaring a 32768x32768 picture (2^30 pixels,
  OpenCV's own cap), with a few bytes of image data;
- :func:`bogus_chunk_png`: a small valid PNG with a tEXt chunk declaring 2^31 - 1 bytes
  (with OpenCV alone: 8 s and +2 GB before it gives up);
- :func:`large_png`: a valid all-black 30000x30000 PNG in 911 KB (OpenCV alone: 4 s,
  +1.8 GB).

Runs in about 10 s (four child processes, each importing OpenCV; building the large PNG
takes ~1 s).
"""

from __future__ import annotations

import json
import logging
import struct
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from shared.image_header import PNG_SIGNATURE
from tools.bench.memory_status import status_kb

#: Peak resident memory of the photo path on any file, MB (issue 15: "under 400 MB").
PEAK_RSS_TARGET_MB = 400.0
#: A child that takes longer has hung, s (generous: shared CI machines).
CHILD_TIMEOUT_S = 120.0


def png_chunk(kind: bytes, body: bytes, declared_length: int | None = None) -> bytes:
    """One PNG chunk: length, type, body, CRC-32 of type and body.

    Args:
        kind: 4 ASCII letters, e.g. ``b"IHDR"``.
        body: the chunk's data.
        declared_length: the length field written (default ``len(body)``).
    """
    length = len(body) if declared_length is None else declared_length
    return struct.pack(">I", length) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _ihdr(width_px: int, height_px: int, bit_depth: int = 8, colour_type: int = 0) -> bytes:
    return png_chunk(b"IHDR", struct.pack(">IIBBBBB", width_px, height_px, bit_depth,
                                          colour_type, 0, 0, 0))


def header_bomb_png(side_px: int = 32768) -> bytes:
    """A PNG of a few dozen bytes declaring a ``side_px`` x ``side_px`` grey picture."""
    return (PNG_SIGNATURE + _ihdr(side_px, side_px) + png_chunk(b"IDAT", zlib.compress(bytes(64)))
            + png_chunk(b"IEND", b""))


def bogus_chunk_png(rng: np.random.Generator, width_px: int = 64, height_px: int = 48) -> bytes:
    """A valid PNG of random grey levels, with a tEXt chunk after IHDR declaring 2^31 - 1 bytes.

    The chunk's CRC is right for its 8 real bytes; its length field lies.
    """
    image = rng.integers(0, 256, (height_px, width_px), dtype=np.uint8)
    png = cv2.imencode(".png", image)[1].tobytes()
    after_ihdr = len(PNG_SIGNATURE) + 25
    lie = png_chunk(b"tEXt", b"Comment\x00", declared_length=(1 << 31) - 1)
    return png[:after_ihdr] + lie + png[after_ihdr:]


def large_png(side_px: int = 30000, rows_per_block: int = 16) -> bytes:
    """A valid all-black ``side_px`` x ``side_px`` 8-bit grey PNG, about side_px^2 / 1000 bytes.

    Built in about a second: after a zlib full flush the compressor forgets what came
    before, so each block of ``rows_per_block`` rows (filter byte 0, then zeros)
    compresses to the same bytes, which are repeated; the Adler-32 of the whole stream
    (RFC 1950) is computed over the rows and written last.
    """
    row = bytes(side_px + 1)
    blocks, rest = divmod(side_px, rows_per_block)
    co = zlib.compressobj(9)
    first = co.compress(row * rows_per_block) + co.flush(zlib.Z_FULL_FLUSH)
    repeated = co.compress(row * rows_per_block) + co.flush(zlib.Z_FULL_FLUSH)
    end = co.compress(row * rest) + co.flush()
    adler = 1
    for _ in range(side_px):
        adler = zlib.adler32(row, adler)
    stream = first + repeated * (blocks - 1) + end[:-4] + struct.pack(">I", adler)
    return (PNG_SIGNATURE + _ihdr(side_px, side_px) + png_chunk(b"IDAT", stream)
            + png_chunk(b"IEND", b""))


def scene(seed: int) -> npt.NDArray[np.uint8]:
    """(600, 800) uint8: a random texture of the default camera's size, the valid photo."""
    from sim.synthetic.image_pairs import texture

    return np.clip(np.rint(texture(np.random.default_rng(seed))), 0, 255).astype(np.uint8)


def measure(seed: int = 0) -> dict[str, object]:
    """Each bomb, and a valid photo, through the robot's photo path in a fresh process.

    Takes about 10 s. Figures per file (``header_bomb``, ``bogus_chunk``, ``large_png``,
    ``valid_photo``): ``bytes``; ``peak_rss_mb``, the child's peak resident memory over
    its whole life (OpenCV and the memory included); ``rss_increase_mb``, how far that
    peak is above the memory resident just before the photo was handed over;
    ``decode_s``, the ``find_photo`` call (reading, checking, decoding, localizing);
    ``refused``, the photo refused as unreadable (an error notice); ``found``, found at a
    key image; and the robot's ``notice``.

    Args:
        seed: the random texture of the valid photo and of the bogus-chunk PNG.

    Returns:
        The figures, ``valid_photo_accepted`` (the valid photo found at its key image)
        and ``targets_met``: every bomb refused, every peak under
        :data:`PEAK_RSS_TARGET_MB`, the valid photo accepted.
    """
    files = {
        "header_bomb": header_bomb_png(),
        "bogus_chunk": bogus_chunk_png(np.random.default_rng(seed)),
        "large_png": large_png(),
        "valid_photo": cv2.imencode(".jpg", scene(seed), [cv2.IMWRITE_JPEG_QUALITY, 90])[1]
        .tobytes(),
    }
    out: dict[str, object] = {}
    with tempfile.TemporaryDirectory(prefix="hostile_images_") as folder:
        for name, data in files.items():
            path = Path(folder) / f"{name}.{'jpg' if name == 'valid_photo' else 'png'}"
            path.write_bytes(data)
            child = subprocess.run(
                [sys.executable, "-m", "tools.bench.hostile_images", str(path), str(seed)],
                capture_output=True, text=True, timeout=CHILD_TIMEOUT_S, check=True)
            out[name] = {"bytes": len(data), **json.loads(child.stdout)}
    bombs = [out[name] for name in ("header_bomb", "bogus_chunk", "large_png")]
    valid = out["valid_photo"]
    assert isinstance(valid, dict)
    out["valid_photo_accepted"] = valid["found"]
    out["targets_met"] = (
        all(isinstance(b, dict) and b["refused"] for b in bombs)
        and all(isinstance(r, dict) and r["peak_rss_mb"] < PEAK_RSS_TARGET_MB
                for r in out.values() if isinstance(r, dict))
        and bool(valid["found"]))
    return out


def _child(photo: Path, seed: int) -> dict[str, object]:
    """In the child: ``find_photo`` on ``photo`` over a one-key-image memory of the scene."""
    from robot.config import VmnavConfig
    from robot.memory.localize import Localizer
    from robot.mode_events import PhotoFound, PhotoNotFound
    from robot.vision.front_end import make_front_end, stored_descriptors
    from robot.worker import find_photo
    from shared.camera_model import CameraModel
    from shared.memory import KeyframeRecord, VisualMemory

    config = VmnavConfig()
    camera = CameraModel.default()
    image = scene(seed)
    features = make_front_end(config.features, camera).describe(image)
    memory = VisualMemory(camera)
    memory.add_path("scene", [KeyframeRecord(t_ns=0, odom_pose=(0.0, 0.0, 0.0), distance_m=0.0,
                                             image=image, pixels_xy=np.array(features.pixels_xy),
                                             patches=stored_descriptors(features))])
    localizer = Localizer.from_memory(memory, config.camera.mount, config.features,
                                      config.localize)
    rss_before_kb = status_kb("VmRSS")
    start = time.perf_counter()
    event = find_photo(photo, localizer, camera)
    decode_s = time.perf_counter() - start
    peak_kb = status_kb("VmHWM")
    assert isinstance(event, PhotoFound | PhotoNotFound)
    # An unreadable or refused photo is an error notice; "not in the memory" a warning.
    refused = isinstance(event, PhotoNotFound) and event.level == logging.ERROR
    return {"peak_rss_mb": round(peak_kb / 1024, 1),
            "rss_increase_mb": round(max(0, peak_kb - rss_before_kb) / 1024, 1),
            "decode_s": round(decode_s, 4), "refused": refused,
            "found": isinstance(event, PhotoFound), "notice": event.text}


if __name__ == "__main__":
    print(json.dumps(_child(Path(sys.argv[1]), int(sys.argv[2]))))
