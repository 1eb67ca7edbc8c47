"""The picture of ``vmnav vision pair --out``: two images side by side with their matches.

Corners are small grey dots, matches that the relative pose rejects thin red lines, its
inliers green lines; a caption gives the counts. Written atomically, as JPEG (quality
90) when the file's name ends in ``.jpg`` or ``.jpeg``, else as PNG.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from robot.vision.two_view import TwoView
from shared.atomic_file import write_bytes_atomic

_CORNER = (160, 160, 160)
_OUTLIER = (40, 40, 220)
_INLIER = (60, 200, 60)
_CAPTION_PX = 28


def pair_matches_image(image_a: npt.NDArray[np.uint8], image_b: npt.NDArray[np.uint8],
                       result: TwoView) -> npt.NDArray[np.uint8]:
    """The picture as a (H, W, 3) uint8 BGR image: a and b side by side, a caption below.

    Args:
        image_a: (H_a, W_a) uint8 grey image a.
        image_b: (H_b, W_b) uint8 grey image b.
        result: what :func:`robot.vision.two_view.two_view` found in them.
    """
    height = max(image_a.shape[0], image_b.shape[0])
    width_a = image_a.shape[1]
    canvas = np.zeros((height + _CAPTION_PX, width_a + image_b.shape[1], 3), np.uint8)
    canvas[: image_a.shape[0], :width_a] = cv2.cvtColor(image_a, cv2.COLOR_GRAY2BGR)
    canvas[: image_b.shape[0], width_a:] = cv2.cvtColor(image_b, cv2.COLOR_GRAY2BGR)
    shift = np.array([width_a, 0.0])
    for x, y in np.vstack([result.corners_a, result.corners_b + shift]):
        cv2.circle(canvas, (round(x), round(y)), 2, _CORNER, -1, cv2.LINE_AA)
    inliers = result.fit.inlier_mask
    # Outliers first, so that inliers are drawn over them.
    for keep, colour, thickness in ((~inliers, _OUTLIER, 1), (inliers, _INLIER, 1)):
        for (xa, ya), (xb, yb) in zip(result.matched_a[keep], result.matched_b[keep] + shift,
                                      strict=True):
            cv2.line(canvas, (round(xa), round(ya)), (round(xb), round(yb)), colour, thickness,
                     cv2.LINE_AA)
    n_inliers = result.fit.n_inliers
    caption = (f"corners {len(result.corners_a)} / {len(result.corners_b)}   matches "
               f"{len(result.matched_a)}: inliers {n_inliers} (green), rejected "
               f"{len(result.matched_a) - n_inliers} (red)")
    cv2.putText(canvas, caption, (8, height + 20), cv2.FONT_HERSHEY_SIMPLEX, 0.55,
                (255, 255, 255), 1, cv2.LINE_AA)
    return canvas


def write_pair_matches(path: Path, image_a: npt.NDArray[np.uint8],
                       image_b: npt.NDArray[np.uint8], result: TwoView) -> None:
    """Draw :func:`pair_matches_image` and write it to ``path`` (module docstring), atomically.

    Raises:
        InputError: the file cannot be written (:mod:`shared.atomic_file`).
    """
    jpeg = path.suffix.lower() in (".jpg", ".jpeg")
    ok, data = cv2.imencode(".jpg" if jpeg else ".png",
                            pair_matches_image(image_a, image_b, result),
                            [cv2.IMWRITE_JPEG_QUALITY, 90] if jpeg else [])
    if not ok:  # encoding a uint8 BGR image cannot fail; kept as a guard, not a path
        raise RuntimeError("cv2.imencode failed on a uint8 BGR image")
    write_bytes_atomic(path, data.tobytes())
