"""``vmnav calibrate --capture``: take calibration views from a camera (the I/O around
:class:`robot.calibration_capture.ViewPicker`).

Frames come from ``cv2.VideoCapture`` through :class:`robot.camera.VideoCaptureSource`
(a device index, a video file or a URL; a live source gives its newest frame, so a slow
board search skips frames rather than falling behind). Each view kept is written as
``view_NNN.png`` into a new folder, with a line saying what it added; the capture ends
when the goal is met, the source ends, or after ``--max-frames``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import CalibrationError, InputError

if TYPE_CHECKING:
    from robot.calibration_capture import CaptureGoal
    from shared.chessboard import Chessboard


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
