"""``vmnav calibrate --capture``: take calibration views from a camera (the I/O around
:class:`robot.calibration_capture.ViewPicker`).

Frames come from ``cv2.VideoCapture`` through :class:`robot.camera.VideoCaptureSource`
(a device index, a video file or a URL; a live source gives its newest frame, so a slow
board search skips frames rather than falling behind). Each view kept is written as
``view_NNN.png`` into a new folder, with a line saying what it added; the capture ends
when the goal is met, the source ends, or after ``--max-frames``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import CalibrationError, InputError
from tools.harness.arg_types import COUNT, COVERAGE, POSITIVE_COUNT

if TYPE_CHECKING:
    from robot.calibration_capture import CaptureGoal
    from shared.chessboard import Chessboard


def add_arguments(p: argparse.ArgumentParser) -> None:
    """``vmnav calibrate``'s capture options."""
    capture = p.add_argument_group(
        "capture", "take the board views from a camera first: a frame is kept when its board "
        "covers parts of the lens's image no kept view covered, until the image is covered")
    capture.add_argument("--capture", metavar="SOURCE",
                         help="cv2.VideoCapture source: device index, video file or URL")
    capture.add_argument("--views", type=Path, metavar="DIR",
                         help="new folder for the views kept (PNG), calibrated from after")
    capture.add_argument("--coverage", type=COVERAGE, metavar="F",
                         help="share of the lens's image to cover [default: 0.8]")
    capture.add_argument("--min-views", type=COUNT, metavar="N",
                         help="views to keep at least [default: 12]")
    capture.add_argument("--max-views", type=COUNT, metavar="N",
                         help="views to keep at most [default: 40]")
    capture.add_argument("--max-frames", type=POSITIVE_COUNT, metavar="N",
                         help="stop after reading N frames [default: until covered or the "
                         "source ends]")


def run_capture(args: argparse.Namespace, board: Chessboard) -> Path:
    """Capture the views ``args`` ask for; the folder they are in.

    Raises:
        CalibrationError: no ``--views`` folder, a bad goal, or too few views kept.
    """
    if args.views is None:
        raise CalibrationError("--views", "--capture needs a new folder for the views")
    capture_views(args.capture, args.views, board, _capture_goal(args), args.max_frames)
    return Path(args.views)


def _capture_goal(args: argparse.Namespace) -> CaptureGoal:
    """``--coverage``, ``--min-views``, ``--max-views`` over the defaults."""
    from robot.calibration_capture import CaptureGoal

    given = {"target": args.coverage, "min_views": args.min_views, "max_views": args.max_views}
    try:
        return CaptureGoal(**{k: v for k, v in given.items() if v is not None})
    except ValueError as e:
        raise CalibrationError("--coverage/--min-views/--max-views", str(e)) from None




def capture_views(source: str, folder: Path, board: Chessboard, goal: CaptureGoal,
                  max_frames: int | None) -> int:
    """Pick views from ``source`` into ``folder`` (created; it must not hold files).

    Returns:
        How many views were kept.

    Raises:
        InputError: ``folder`` exists and is not an empty folder, or cannot be written;
            the source is a file that does not exist.
        TransportError: the source does not open or gives no frame.
        CalibrationError: fewer views than ``goal.min_views`` were kept.
    """
    import cv2

    from robot.calibration_capture import ViewPicker
    from robot.camera import VideoCaptureSource
    from robot.config import CameraSourceConfig
    from shared.atomic_file import write_bytes_atomic
    from shared.clock import WallClock

    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise InputError(folder, "exists and is not an empty folder: the views go into a new one")
    picker = ViewPicker(board, goal)
    frames = boards = 0
    with VideoCaptureSource(CameraSourceConfig(source=source), WallClock()) as camera:
        width, height = camera.size_wh
        print(f"capturing from {source} ({width}x{height}): hold the {board.cols}x"
              f"{board.rows} board in front of the lens, all over the image, the rim too",
              flush=True)
        while not picker.done and (max_frames is None or frames < max_frames):
            frame = camera.read()
            if frame is None:
                break
            frames += 1
            look = picker.look(frame[1])
            boards += look.corners is not None
            if not look.kept:
                continue
            path = folder / f"view_{picker.kept - 1:03d}.png"
            _, png = cv2.imencode(".png", frame[1])
            try:
                folder.mkdir(parents=True, exist_ok=True)
                write_bytes_atomic(path, png.tobytes())
            except OSError as e:
                raise InputError(path, f"cannot write the view: {e.strerror}") from None
            print(f"  {path.name}: frame {frames}, {look.new_cells} new cells; coverage "
                  f"{100 * look.coverage:.0f} % of the lens's image", flush=True)
    print(f"read {frames} frames, board in {boards}, kept {picker.kept} views; coverage "
          f"{100 * picker.coverage:.0f} % (goal {100 * goal.target:.0f} %)", flush=True)
    if picker.kept < goal.min_views:
        raise CalibrationError(source, f"kept {picker.kept} views, need {goal.min_views}: "
                               "show the whole board in more places")
    if picker.coverage < goal.target:
        print(f"warning: the views cover {100 * picker.coverage:.0f} % of the lens's image "
              f"(goal {100 * goal.target:.0f} %): boards near the rim pin the model down "
              "where the lens bends most", flush=True)
    return picker.kept
