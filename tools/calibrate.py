"""``vmnav calibrate``: calibrate the fisheye camera from chessboard images.

Reads every ``.png``/``.jpg``/``.jpeg``/``.bmp`` image of a folder (sorted by
name), finds the board in each, fits the unified sphere model with
``cv2.omnidir.calibrate`` (:mod:`robot.camera_calibration`), prints what each
image contributed and the result, and writes the calibration JSON
(:mod:`shared.calibration`).
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path
from typing import TYPE_CHECKING

from shared.chessboard import Chessboard
from shared.errors import CalibrationError

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp")


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav calibrate``."""
    p = subparsers.add_parser(
        "calibrate",
        help="calibrate the fisheye camera from chessboard images",
        description="Find a chessboard in every image of IMAGES_DIR (png, jpg, jpeg, bmp), "
        "fit the unified sphere camera model with cv2.omnidir.calibrate and write the "
        "calibration JSON.",
    )
    p.add_argument("images_dir", metavar="IMAGES_DIR", type=Path, help="folder of board images")
    p.add_argument(
        "--pattern",
        required=True,
        metavar="COLSxROWS",
        help="inner corners of the board, e.g. 9x6 for a board of 10x7 squares",
    )
    p.add_argument("--square", required=True, metavar="M", help="side of one square, m")
    p.add_argument(
        "-o", "--output", required=True, type=Path, metavar="FILE", help="calibration JSON to write"
    )
    p.add_argument(
        "--fov",
        default="185",
        metavar="DEG",
        help="full field of view of the lens, degrees (from its data sheet) [default: 185]",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Calibrate, print the report, write the file; returns the exit code."""
    from robot.camera_calibration import calibrate_omnidir, find_board_corners
    from shared.calibration import write_camera

    board = _board(args.pattern, args.square)
    fov_deg = _number("--fov", args.fov)
    if not 0.0 < fov_deg < 360.0:
        raise CalibrationError("--fov", f"must be in (0, 360) degrees, got {args.fov}")
    paths = _image_paths(args.images_dir)
    images, size = _read_images(paths)
    detections = {
        path: find_board_corners(image, board) for path, image in zip(paths, images, strict=True)
    }
    found = [path for path in paths if detections[path] is not None]
    print(
        f"{len(paths)} images in {args.images_dir}, board {board.cols}x{board.rows} inner "
        f"corners, {board.square_m:g} m squares; board found in {len(found)}"
    )
    result = calibrate_omnidir(
        [detections[path] for path in found], board, size, fov_deg=fov_deg, where=args.images_dir
    )

    view_rms = {found[k]: rms for k, rms in zip(result.used, result.view_rms_px, strict=True)}
    for path in paths:
        if path in view_rms:
            status = f"used, rms {view_rms[path]:.3f} px"
        elif path in found:
            status = "board found, rejected at initialization"
        else:
            status = "board not found"
        print(f"  {path.name}: {status}")
    camera = result.camera
    (fx, skew, cx), (_, fy, cy) = camera.K[0], camera.K[1]
    print(
        f"calibrated on {len(result.used)} of {len(paths)} images: "
        f"RMS reprojection error {result.rms_px:.3f} px"
    )
    print(f"  K: fx {fx:.3f}  fy {fy:.3f}  cx {cx:.3f}  cy {cy:.3f}  skew {skew:g}  (px)")
    print(f"  xi: {camera.xi:.6f}")
    print("  D (k1 k2 p1 p2): " + " ".join(f"{d:.6g}" for d in camera.D))
    source = (
        f"vmnav calibrate: {len(result.used)} of {len(paths)} images in {args.images_dir}, "
        f"board {board.cols}x{board.rows} of {board.square_m:g} m, fov {fov_deg:g} deg given"
    )
    write_camera(args.output, camera, rms_px=result.rms_px, source=source)
    print(f"wrote {args.output}")
    return 0


def _board(pattern: str, square: str) -> Chessboard:
    """The board from ``--pattern COLSxROWS`` and ``--square M``."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", pattern)
    if match is None:
        raise CalibrationError(
            "--pattern", f"expected inner corners as COLSxROWS like 9x6, got {pattern!r}"
        )
    cols, rows = int(match[1]), int(match[2])
    if cols < 2 or rows < 2:
        raise CalibrationError("--pattern", f"need at least 2x2 inner corners, got {pattern!r}")
    square_m = _number("--square", square)
    if square_m <= 0.0:
        raise CalibrationError("--square", f"must be > 0 m, got {square}")
    return Chessboard(cols=cols, rows=rows, square_m=square_m)


def _number(option: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise CalibrationError(option, f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise CalibrationError(option, f"expected a finite number, got {text!r}")
    return value


def _image_paths(folder: Path) -> list[Path]:
    """The images of ``folder``, sorted by name."""
    if not folder.exists():
        raise CalibrationError(folder, "folder not found")
    if not folder.is_dir():
        raise CalibrationError(folder, "not a folder")
    try:
        paths = sorted(
            p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
        )
    except OSError as e:
        raise CalibrationError(folder, f"cannot list the folder: {e.strerror}") from None
    if not paths:
        raise CalibrationError(folder, f"no images ({', '.join(IMAGE_SUFFIXES)}) in this folder")
    return paths


def _read_images(paths: list[Path]) -> tuple[list[NDArray[np.uint8]], tuple[int, int]]:
    """The images as (H, W) uint8 grey, and their common ``(width, height)``."""
    import cv2

    images = []
    for path in paths:
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise CalibrationError(path, "cannot read the image (corrupt or not an image)")
        if images and image.shape != images[0].shape:
            (h, w), (h0, w0) = image.shape, images[0].shape
            raise CalibrationError(path, f"image is {w}x{h} but {paths[0].name} is {w0}x{h0}")
        images.append(image)
    height, width = images[0].shape
    return images, (width, height)
