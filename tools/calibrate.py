"""``vmnav calibrate``: calibrate the fisheye camera, or import a calibration.

From chessboard images: reads every image of a folder in a format OpenCV reads and
:mod:`shared.image_decode` checks (PNG, JPEG, PGM/PPM/PBM, BMP, TIFF, WebP; sorted by
name, numbers in numeric order), finds the board in each, fits the unified sphere model with
``cv2.omnidir.calibrate`` (:mod:`robot.camera_calibration`), prints what each image
contributed, a warning for each duplicate or outlier view
(:mod:`robot.calibration_checks`) and the result, and writes the calibration JSON
(:mod:`shared.calibration`).

``--from-equidistant YAML``: reads a Kannala-Brandt calibration
(:mod:`shared.kannala_brandt_yaml`), fits the unified model to it
(:func:`shared.kannala_brandt.fit_unified`), prints the fit and its residual, and
writes the calibration JSON.

Either way the output file is written atomically, and an existing file is replaced
only if ``vmnav calibrate`` wrote it.
"""

from __future__ import annotations

import argparse
import math
import re
import statistics
from pathlib import Path

from shared.chessboard import Chessboard
from shared.errors import CalibrationError
from tools import calibrate_capture_cmd
from tools.harness.image_folder import image_paths, read_images

#: What the ``source`` field of every file this command writes starts with.
WRITER = "vmnav calibrate"


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav calibrate``."""
    p = subparsers.add_parser(
        "calibrate",
        help="calibrate from chessboards, or import a calibration",
        description="Find a chessboard in every image of IMAGES_DIR (png, jpg, pgm, ppm, "
        "pbm, bmp, tif, webp), fit the unified sphere camera model with "
        "cv2.omnidir.calibrate and write the calibration JSON; or, with --from-equidistant, "
        "fit the unified model to an equidistant (Kannala-Brandt) calibration and write it.",
    )
    p.add_argument("images_dir", metavar="IMAGES_DIR", type=Path, nargs="?",
                   help="folder of board images")
    calibrate_capture_cmd.add_arguments(p)
    p.add_argument("--from-equidistant", type=Path, metavar="YAML",
                   help="import this equidistant (cv2.fisheye) calibration instead")
    p.add_argument(
        "--pattern",
        metavar="COLSxROWS",
        help="inner corners of the board, e.g. 9x6 for a board of 10x7 squares",
    )
    p.add_argument("--square", metavar="M", help="side of one square, m")
    p.add_argument("-o", "--output", "--out", required=True, type=Path, metavar="FILE",
                   help="calibration JSON to write")
    p.add_argument(
        "--fov",
        metavar="DEG",
        help="full field of view of the lens, degrees (from its data sheet) [default: 185]",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Calibrate or import, print the report, write the file; returns the exit code."""
    from shared.calibration import check_replaceable

    given = [args.images_dir is not None, args.from_equidistant is not None,
             args.capture is not None]
    if sum(given) != 1:
        raise CalibrationError("IMAGES_DIR", "give a folder of board images, --capture SOURCE "
                                             "or --from-equidistant YAML (one of the three)")
    check_replaceable(args.output, WRITER)
    if args.capture is not None:
        board = _board(args.pattern, args.square)
        _fov_deg(args.fov)
        args.images_dir = calibrate_capture_cmd.run_capture(args, board)
    if args.from_equidistant is not None:
        from tools.calibrate_equidistant_cmd import import_equidistant

        for option, value in (("--pattern", args.pattern), ("--square", args.square),
                              ("--fov", args.fov)):
            if value is not None:
                raise CalibrationError(option, "not used with --from-equidistant (the field "
                                               "of view comes from the image's corners)")
        return import_equidistant(args.from_equidistant, args.output, WRITER)
    return _calibrate(args)


def _calibrate(args: argparse.Namespace) -> int:
    from robot.calibration_checks import duplicate_views, outlier_views
    from robot.camera_calibration import calibrate_omnidir, find_board_corners
    from shared.calibration import write_camera

    board = _board(args.pattern, args.square)
    fov_deg = _fov_deg(args.fov)
    paths = image_paths(args.images_dir)
    images, size = read_images(paths)
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
    for dup in duplicate_views([detections[path] for path in found], board):
        print(f"warning: {found[dup.later].name}: nearly the same board pose as "
              f"{found[dup.earlier].name} (corners {dup.rms_px:.1f} px apart, RMS): a duplicate "
              "view, drop or retake it")
    median_px = statistics.median(result.view_rms_px)
    for k in outlier_views(result.view_rms_px):
        print(f"warning: {found[result.used[k]].name}: rms {result.view_rms_px[k]:.3f} px, "
              f"{result.view_rms_px[k] / median_px:.1f}x the median view's {median_px:.3f} px: "
              "an outlier view (blurred or misdetected board?), check it")
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
        f"{WRITER}: {len(result.used)} of {len(paths)} images in {args.images_dir}, "
        f"board {board.cols}x{board.rows} of {board.square_m:g} m, fov {fov_deg:g} deg given"
    )
    write_camera(args.output, camera, rms_px=result.rms_px, source=source)
    print(f"wrote {args.output}")
    return 0


def _fov_deg(text: str | None) -> float:
    """``--fov`` in degrees (185 when not given)."""
    fov_deg = _number("--fov", "185" if text is None else text)
    if not 0.0 < fov_deg < 360.0:
        raise CalibrationError("--fov", f"must be in (0, 360) degrees, got {text}")
    return fov_deg


def _board(pattern: str | None, square: str | None) -> Chessboard:
    """The board from ``--pattern COLSxROWS`` and ``--square M``."""
    if pattern is None or square is None:
        raise CalibrationError("--pattern/--square", "both are needed to calibrate from images")
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
