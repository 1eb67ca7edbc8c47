"""OpenCV's descriptors as front-end methods: ORB, TEBLID, BEBLID on FAST corners spread
over a grid, and AKAZE and SIFT on their own detectors.

Why a grid (docs/front-end.md): a detector that keeps the strongest responses of a
frame puts them where the contrast is highest, on lamps and a poster, and leaves the
rest of the view empty; the relative pose then rests on a small part of the sphere.
Here (``fast`` methods):

* corners: FAST-9 (Rosten and Drummond, ECCV 2006) with an *absolute* contrast
  threshold ``fast_threshold`` (grey levels), and ``fast_threshold_low`` in the cells
  that found fewer than their share: a dim part of the frame keeps its corners,
  however bright the rest (a lamp, a window);
* spread: the image is cut into square cells, ``grid_cells`` along its longer side,
  and each cell keeps its strongest ``ceil(max_corners / cells in the lens)`` corners
  (FAST's non-maximum suppression keeps them apart);
* sub-pixel positions: ``cv2.cornerSubPix`` as for the paper's Harris corners;
* descriptors: upright (angle 0: the camera is level on a ground robot, and a turn
  of the robot does not rotate the image about the optical axis), on a window of
  ``descriptor_size_deg`` (in pixels through the lens): ORB's rBRIEF (Rublee et al.,
  ICCV 2011), TEBLID (Suárez et al., 2021) or BEBLID (Suárez et al., 2020), bit
  strings matched by Hamming distance.

AKAZE (Alcantarilla et al., BMVC 2013; bit strings) and SIFT (Lowe, IJCV 2004;
128 floats, here unit rows) keep their own scale-space detectors, strongest
``max_corners`` first; they are slower and offered for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig
from robot.vision.features import (
    BoolImage,
    GreyImage,
    Keypoints,
    PixelSizes,
    allowed_centres,
    check_image,
    refine_subpixel,
)

#: Bytes of each method's descriptor.
DESCRIPTOR_BYTES = {"orb": 32, "teblid": 32, "beblid": 32, "akaze": 61}
#: SIFT's descriptor length, floats.
SIFT_LENGTH = 128

Detector = Callable[[GreyImage, FeatureConfig, BoolImage | None, PixelSizes], Keypoints]
"""A method's detector: (image, config, mask or None, the windows in pixels for the lens)
-> keypoints inside the mask."""


def detect_grid_fast(image: GreyImage, config: FeatureConfig, mask: BoolImage | None,
                     margin_px: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float32]]:
    """FAST corners spread over a grid (module docstring).

    Args:
        image: (H, W) uint8, checked.
        config: thresholds, grid, cap and sub-pixel window.
        mask: (H, W) bool or None, checked.
        margin_px: corners keep this far inside the mask and the image (descriptor window).

    Returns:
        ``(pixels_xy (N, 2) float64, response (N,) float32)``, strongest first.
    """
    allowed = allowed_centres(image.shape, margin_px + config.subpixel_half_window_px, mask)
    if allowed is None:
        return np.zeros((0, 2)), np.zeros(0, np.float32)
    grid = _Grid(image.shape, allowed, config)
    pixels, response = _fast(image, allowed, config.fast_threshold, (0, 0))
    if config.fast_threshold_low < config.fast_threshold:
        pixels, response = _search_weak_cells(image, allowed, grid, pixels, response, config)
    keep = grid.spread(pixels, response)
    pixels = refine_subpixel(image, pixels[keep], config.subpixel_half_window_px)
    distinct = _distinct(pixels)
    return pixels[distinct], response[keep][distinct]


#: Two refined corners closer than this are one corner, px.
_SAME_CORNER_PX = 1.0


def _distinct(pixels: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:
    """(N,) False for a corner within ``_SAME_CORNER_PX`` of a stronger (earlier) one:
    FAST fires a few pixels around one saddle, and sub-pixel refinement moves them all
    onto it (same point, same descriptor: a tie no matching can break).

    Sorted by x, each corner is compared with the k-th next while any such pair lies
    within the distance in x (a few k): 0.04 ms for 300 corners, where all pairs took 2.4.
    """
    order = np.argsort(pixels[:, 0], kind="stable")
    xs, ys = pixels[order, 0], pixels[order, 1]
    weaker = np.zeros(len(pixels), bool)
    for k in range(1, len(pixels)):
        i = np.flatnonzero(xs[k:] - xs[:-k] < _SAME_CORNER_PX)
        if i.size == 0:
            break
        j = i + k
        close = (xs[j] - xs[i]) ** 2 + (ys[j] - ys[i]) ** 2 < _SAME_CORNER_PX ** 2
        weaker[np.maximum(order[i[close]], order[j[close]])] = True
    return ~weaker


def _fast(image: GreyImage, allowed: npt.NDArray[np.uint8], threshold: int,
          origin_xy: tuple[int, int]) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float32]]:
    """FAST-9 corners with non-maximum suppression, shifted by ``origin_xy`` (an ROI's)."""
    found = cv2.FastFeatureDetector_create(threshold, True).detect(image, allowed)
    if not found:
        return np.zeros((0, 2)), np.zeros(0, np.float32)
    pixels = cv2.KeyPoint_convert(found).astype(np.float64) + origin_xy
    return pixels, np.fromiter((k.response for k in found), np.float32, len(found))


class _Grid:
    """Square cells, ``grid_cells`` along the image's longer side; the cells holding any
    allowed pixel share ``max_corners``."""

    def __init__(self, shape: tuple[int, ...], allowed: npt.NDArray[np.uint8],
                 config: FeatureConfig) -> None:
        height, width = shape
        self.side = max(height, width) / config.grid_cells
        self.n_cols, n_rows = math.ceil(width / self.side), math.ceil(height / self.side)
        coverage = cv2.resize(allowed, (self.n_cols, n_rows), interpolation=cv2.INTER_AREA)
        self.lens_cells = np.flatnonzero(coverage.ravel())
        self.per_cell = math.ceil(config.max_corners / max(1, len(self.lens_cells)))
        self.max_corners = config.max_corners
        self.shape = (height, width)

    def cell(self, pixels: npt.NDArray[np.float64]) -> npt.NDArray[np.intp]:
        """(N,) the cell of each pixel, row-major."""
        rows = (pixels[:, 1] // self.side).astype(np.intp)
        return rows * self.n_cols + (pixels[:, 0] // self.side).astype(np.intp)

    def bounds(self, cell: int) -> tuple[int, int, int, int]:
        """The cell's pixel rectangle (x0, y0, x1, y1), x1 and y1 excluded."""
        row, col = divmod(cell, self.n_cols)
        height, width = self.shape
        return (round(col * self.side), round(row * self.side),
                min(width, round((col + 1) * self.side)), min(height, round((row + 1) * self.side)))

    def spread(self, pixels: npt.NDArray[np.float64], response: npt.NDArray[np.float32]
               ) -> npt.NDArray[np.intp]:
        """Indices of the corners each cell keeps (its strongest ``per_cell``), strongest
        first overall."""
        cell = self.cell(pixels)
        order = np.lexsort((-response, cell))
        cells = cell[order]
        first = np.searchsorted(cells, cells, side="left")
        keep = order[np.arange(len(order)) - first < self.per_cell]
        return keep[np.argsort(-response[keep], kind="stable")][: self.max_corners]


#: FAST skips this many pixels at an image's border (its circle's radius).
_FAST_BORDER_PX = 3


def _search_weak_cells(image: GreyImage, allowed: npt.NDArray[np.uint8], grid: _Grid,
                       pixels: npt.NDArray[np.float64], response: npt.NDArray[np.float32],
                       config: FeatureConfig
                       ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float32]]:
    """The corners, with those of the lens cells holding fewer than their share replaced by
    FAST's at ``fast_threshold_low``: a dim or low-contrast part of the view keeps corners
    (a local threshold, as ORB-SLAM's per-cell FAST)."""
    cell = grid.cell(pixels)
    counts = np.bincount(cell, minlength=grid.lens_cells.max(initial=0) + 1)
    weak = [int(c) for c in grid.lens_cells if counts[c] < grid.per_cell]
    if not weak:
        return pixels, response
    keep = ~np.isin(cell, weak)
    parts_xy, parts_r = [pixels[keep]], [response[keep]]
    height, width = grid.shape
    b = _FAST_BORDER_PX
    for c in weak:
        x0, y0, x1, y1 = grid.bounds(c)
        ex0, ey0, ex1, ey1 = max(0, x0 - b), max(0, y0 - b), min(width, x1 + b), min(height, y1 + b)
        xy, r = _fast(image[ey0:ey1, ex0:ex1], allowed[ey0:ey1, ex0:ex1],
                      config.fast_threshold_low, (ex0, ey0))
        inside = (xy[:, 0] >= x0) & (xy[:, 0] < x1) & (xy[:, 1] >= y0) & (xy[:, 1] < y1)
        parts_xy.append(xy[inside])
        parts_r.append(r[inside])
    return np.concatenate(parts_xy), np.concatenate(parts_r)


def _binary_on_fast(extractor: Any) -> Detector:
    """A method: FAST grid corners described by ``extractor`` (upright, one scale)."""

    def detect(image: GreyImage, config: FeatureConfig, mask: BoolImage | None,
               sizes: PixelSizes) -> Keypoints:
        image, mask = check_image(image, mask)
        size = sizes.descriptor_px
        # rBRIEF and the BLIDs sample up to about size / sqrt(2) from the centre.
        margin = math.ceil(size / math.sqrt(2)) + 1
        pixels, response = detect_grid_fast(image, config, mask, margin)
        keypoints = [cv2.KeyPoint(float(x), float(y), float(size), 0.0, float(r), 0, i)
                     for i, ((x, y), r) in enumerate(zip(pixels, response, strict=True))]
        return _described(extractor, image, keypoints, pixels, response)

    return detect


def _described(extractor: Any, image: GreyImage, keypoints: Sequence[Any],
               pixels: npt.NDArray[np.float64], response: npt.NDArray[np.float32]) -> Keypoints:
    """Describe ``keypoints`` (class_id = row of ``pixels``); extractors may drop some."""
    empty = Keypoints(np.zeros((0, 2)), np.zeros((0, extractor.descriptorSize()), np.uint8),
                      np.zeros(0, np.float32))
    if not keypoints:
        return empty
    kept, descriptors = extractor.compute(image, keypoints)
    if descriptors is None or not kept:
        return empty
    rows = np.fromiter((k.class_id for k in kept), np.intp, len(kept))
    return Keypoints(pixels[rows], np.ascontiguousarray(descriptors), response[rows])


def _scale_space(detector: Any, binary: bool) -> Detector:
    """A method: a detector-descriptor's own keypoints, strongest ``max_corners`` first."""

    def detect(image: GreyImage, config: FeatureConfig, mask: BoolImage | None,
               sizes: PixelSizes) -> Keypoints:
        image, mask = check_image(image, mask)
        allowed = allowed_centres(image.shape, 1, mask)
        length = DESCRIPTOR_BYTES["akaze"] if binary else SIFT_LENGTH
        empty = Keypoints(np.zeros((0, 2)), np.zeros((0, length), np.uint8 if binary
                                                     else np.float32), np.zeros(0, np.float32))
        if allowed is None:
            return empty
        found, descriptors = detector.detectAndCompute(image, allowed)
        if not found:
            return empty
        response = np.fromiter((k.response for k in found), np.float32, len(found))
        order = np.argsort(-response, kind="stable")[: config.max_corners]
        pixels = cv2.KeyPoint_convert(found).astype(np.float64)[order]
        descriptors = descriptors[order]
        if not binary:
            norms = np.linalg.norm(descriptors, axis=1, keepdims=True)
            descriptors = descriptors / np.where(norms > 0, norms, 1.0)
        return Keypoints(pixels, np.ascontiguousarray(descriptors), response[order])

    return detect


def opencv_detector(method: str) -> Detector:
    """The detector of one of OpenCV's methods (``orb``, ``teblid``, ``beblid``, ``akaze``,
    ``sift``), its OpenCV objects made now (one per front end: they are not shared).

    Raises:
        KeyError: another method.
    """
    makers: dict[str, Callable[[], Detector]] = {
        "orb": lambda: _binary_on_fast(cv2.ORB_create(nlevels=1)),
        "teblid": lambda: _binary_on_fast(
            cv2.xfeatures2d.TEBLID_create(1.0, cv2.xfeatures2d.TEBLID_SIZE_256_BITS)),
        "beblid": lambda: _binary_on_fast(
            cv2.xfeatures2d.BEBLID_create(1.0, cv2.xfeatures2d.BEBLID_SIZE_256_BITS)),
        "akaze": lambda: _scale_space(cv2.xfeatures2d.AKAZE_create(), binary=True),
        "sift": lambda: _scale_space(cv2.SIFT_create(), binary=False),
    }
    return makers[method]()
