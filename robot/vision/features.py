"""The features of one image (:class:`Features`), and the paper's detector: Harris corners
with zero-mean, unit-norm patch descriptors for ZNCC matching.

Every front-end method (:mod:`robot.vision.front_end`) returns :class:`Features`;
this module also holds the ``harris-zncc`` method's detector, :func:`detect_harris`.

The paper's front end (Courbon et al., ICARCV 2008, sec. III-A): "Interest points
are detected in each image with Harris corner detector [7]" and compared by Zero
Normalized Cross Correlation of their neighbourhoods. Here:

* corners: ``cv2.goodFeaturesToTrackWithQuality`` with the Harris response
  R = det(M) - k trace(M)^2 (Harris & Stephens 1988), relative quality threshold,
  greedy minimum distance, strongest first. Measured faster than ``cv2.cornerHarris``
  plus numpy non-maximum suppression (2.0 ms against 4.5 ms at 800x600, one core);
* sub-pixel positions: ``cv2.cornerSubPix`` (Förstner 1987). Harris maxima sit up
  to a pixel inside a corner, which cancels under pure translation but not under
  rotation or scale; refinement cut the median error of matched pixels from
  0.55 px to 0.16 px on synthetic pairs for 0.4 ms per frame;
* descriptors: the P x P patch around the rounded sub-pixel position, made
  zero-mean and unit-norm, so that ZNCC between two patches is their dot product
  and is invariant to affine brightness changes ``a I + b`` with a > 0.

No patch crosses the image border or leaves the validity mask: candidates are
restricted to the mask eroded by the patch half size plus the sub-pixel window
(``cornerSubPix`` gives up on moves longer than its half window).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from robot.config import FeatureConfig
from shared.camera_model import CameraModel
from shared.errors import ShapeError, check_shape

PixelsXY = npt.NDArray[np.float64]
"""(N, 2) float64 pixel coordinates (x right, y down; centre of the top-left pixel is (0, 0))."""
Bearings = npt.NDArray[np.float64]
"""(N, 3) float64 unit rows, camera frame (x right, y down, z along the optical axis)."""
Descriptors = npt.NDArray[Any]
"""(N, D) descriptors of one method: float32 unit-norm rows (ZNCC patches, SIFT) or uint8
bit strings (ORB, AKAZE, TEBLID, BEBLID; D bytes = 8 D bits)."""
Patches = npt.NDArray[np.float32]
"""(N, P*P) float32 row-major patches, each row zero-mean and unit-norm (or all zero if flat)."""
Responses = npt.NDArray[np.float32]
"""(N,) float32 detector responses (Harris: OpenCV's scale, gradients normalised by 255)."""
GreyImage = npt.NDArray[np.uint8]
"""(H, W) uint8 grey image."""
BoolImage = npt.NDArray[np.bool_]
"""(H, W) bool image mask."""

#: Descriptor dtypes a :class:`Features` holds: real-valued unit rows, or packed bits.
DESCRIPTOR_DTYPES = (np.dtype(np.float32), np.dtype(np.uint8))

#: cv2.cornerSubPix stops after this many iterations or a move shorter than _SUBPIX_EPS_PX.
_SUBPIX_MAX_ITER = 10
_SUBPIX_EPS_PX = 0.01
_SUBPIX_CRITERIA = (
    cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, _SUBPIX_MAX_ITER, _SUBPIX_EPS_PX
)
#: Sobel aperture of the Harris matrix (OpenCV's cornerHarris default).
_GRADIENT_SIZE = 3
#: Patches with a norm below this (grey levels) are flat: their descriptor is all zeros.
_FLAT_NORM = 1e-6


@dataclass(frozen=True, slots=True, eq=False)
class Features:
    """Points of one image with their descriptors and bearings, strongest response first.

    What :meth:`robot.vision.front_end.FrontEnd.describe` returns, whatever the method.
    The arrays are read-only views.

    Attributes:
        pixels_xy: (N, 2) float64 point positions, px (sub-pixel where the method refines).
        descriptors: (N, D) float32 unit-norm rows (the dot product of two rows is
            their similarity in [-1, 1]; for ZNCC patches, the ZNCC score) or uint8
            packed bits (compared by Hamming distance).
        response: (N,) float32 detector responses (zero for stored key images).
        bearings: (N, 3) float64 unit rows, camera frame: the camera model's lift of
            ``pixels_xy`` (the row is (0, 0, 1) where the pixel has no valid ray).
    """

    pixels_xy: PixelsXY
    descriptors: Descriptors
    response: Responses
    bearings: Bearings

    def __post_init__(self) -> None:
        # Views, so that making them read-only leaves the caller's arrays alone.
        pixels = np.asarray(self.pixels_xy, dtype=np.float64).view()
        descriptors = np.asarray(self.descriptors)
        if descriptors.dtype.kind == "f":
            descriptors = descriptors.astype(np.float32, copy=False)
        descriptors = descriptors.view()
        response = np.asarray(self.response, dtype=np.float32).view()
        bearings = np.asarray(self.bearings, dtype=np.float64).view()
        check_shape("pixels_xy", pixels.shape, (None, 2))
        n = pixels.shape[0]
        check_shape("descriptors", descriptors.shape, (n, None))
        check_shape("response", response.shape, (n,))
        check_shape("bearings", bearings.shape, (n, 3))
        if descriptors.dtype not in DESCRIPTOR_DTYPES:
            raise TypeError(f"descriptors: expected floats or uint8, got {descriptors.dtype}")
        if descriptors.shape[1] == 0:
            raise ShapeError(f"descriptors: rows are empty, shape {descriptors.shape}")
        for name, array in (("pixels_xy", pixels), ("descriptors", descriptors),
                            ("response", response), ("bearings", bearings)):
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def __len__(self) -> int:
        return int(self.pixels_xy.shape[0])

    @property
    def binary(self) -> bool:
        """The descriptors are packed bits (Hamming distance), not unit rows."""
        return bool(self.descriptors.dtype == np.uint8)

    @classmethod
    def empty(cls, descriptor_length: int, dtype: npt.DTypeLike = np.float32) -> Features:
        """No features, with arrays of the right shapes for descriptors of that length."""
        return cls(
            pixels_xy=np.zeros((0, 2)),
            descriptors=np.zeros((0, descriptor_length), dtype=dtype),
            response=np.zeros(0, dtype=np.float32),
            bearings=np.zeros((0, 3)),
        )

    def subset(self, rows: npt.ArrayLike) -> Features:
        """The features at ``rows`` ((K,) int indices or (N,) bool), in that order."""
        return Features(self.pixels_xy[rows], self.descriptors[rows], self.response[rows],
                        self.bearings[rows])


def pixels_per_radian(camera: CameraModel) -> float:
    """The lens's scale at the image centre, px/rad (mean of x and y).

    Unified model (Mei and Rives, ICRA 2007): a ray at angle theta off the axis lands
    r = f sin(theta) / (cos(theta) + xi) from the centre, so dr/dtheta = f / (1 + xi) at
    theta = 0 (first-order distortion k1 does not change it). 174 px/rad on the default
    lens, 366 on the MYNT EYE's.
    """
    return float((camera.K[0, 0] + camera.K[1, 1]) / 2.0 / (1.0 + camera.xi))


@dataclass(frozen=True, slots=True)
class PixelSizes:
    """The front end's windows in pixels for one lens: ``FeatureConfig``'s angles times the
    lens's scale at the image centre (:func:`pixels_per_radian`).

    Attributes:
        patch_px: side P of a ZNCC patch, odd, >= 3.
        min_distance_px: least distance between two Harris corners.
        descriptor_px: side of a binary descriptor's window, >= 7.
    """

    patch_px: int
    min_distance_px: float
    descriptor_px: int

    @classmethod
    def for_lens(cls, config: FeatureConfig, px_per_rad: float) -> PixelSizes:
        """The sizes of ``config``'s angles on a lens of ``px_per_rad``."""
        def px(deg: float) -> float:
            return math.radians(deg) * px_per_rad

        return cls(patch_px=max(3, 2 * round((px(config.patch_size_deg) - 1) / 2) + 1),
                   min_distance_px=px(config.min_distance_deg),
                   descriptor_px=max(7, round(px(config.descriptor_size_deg))))

    @classmethod
    def for_camera(cls, config: FeatureConfig, camera: CameraModel) -> PixelSizes:
        """The sizes of ``config``'s angles on ``camera``."""
        return cls.for_lens(config, pixels_per_radian(camera))


@dataclass(frozen=True, slots=True, eq=False)
class Keypoints:
    """What a detector found, before the camera model lifts it (:class:`Features` less bearings).

    Attributes:
        pixels_xy: (N, 2) float64 positions, px.
        descriptors: (N, D) float32 unit rows or uint8 packed bits.
        response: (N,) float32 detector responses, strongest first.
    """

    pixels_xy: PixelsXY
    descriptors: Descriptors
    response: Responses

    def __len__(self) -> int:
        return int(self.pixels_xy.shape[0])


def detect_harris(
    image: GreyImage, config: FeatureConfig, mask: BoolImage | None = None,
    sizes: PixelSizes | None = None,
) -> Keypoints:
    """Detect Harris corners and extract their ZNCC patches (the paper's front end).

    Args:
        image: (H, W) uint8 grey image.
        config: detector and patch parameters.
        mask: (H, W) bool, True where pixels are valid (e.g. inside the fisheye
            image circle); None = the whole image. Every returned patch lies
            within the mask and the image.
        sizes: the patch and spacing in pixels for the lens; None = the default lens's
            (:meth:`PixelSizes.for_camera` of ``CameraModel.default()``).

    Returns:
        Up to ``config.max_corners`` corners, strongest first, with (N, P*P) float32
        zero-mean unit-norm patches; empty (with the right shapes) when the image
        is too small, flat or fully masked.

    Raises:
        ShapeError: ``image`` is not 2-D, or ``mask`` differs from it in shape.
        TypeError: ``image`` is not uint8 or ``mask`` is not bool.
    """
    image, mask = check_image(image, mask)
    sizes = sizes or PixelSizes.for_camera(config, CameraModel.default())
    side = sizes.patch_px
    half = side // 2
    margin = half + config.subpixel_half_window_px
    allowed = allowed_centres(image.shape, margin, mask)
    if allowed is None:
        return _no_corners(side)
    corners, quality = cv2.goodFeaturesToTrackWithQuality(
        image, config.max_corners, config.quality_level, sizes.min_distance_px, allowed,
        blockSize=config.block_size_px, gradientSize=_GRADIENT_SIZE,
        useHarrisDetector=True, k=config.harris_k,
    )
    if corners is None:
        return _no_corners(side)
    pixels_xy = refine_subpixel(image, corners.reshape(-1, 2), config.subpixel_half_window_px)
    # cornerSubPix reverts any move longer than its half window, so the rounded
    # centre stays within `margin` of an allowed pixel; the clip only guards rounding.
    height, width = image.shape
    cols = np.clip(np.rint(pixels_xy[:, 0]).astype(np.intp), half, width - 1 - half)
    rows = np.clip(np.rint(pixels_xy[:, 1]).astype(np.intp), half, height - 1 - half)
    patches = _normalised_patches(image, rows, cols, side)
    return Keypoints(pixels_xy=pixels_xy, descriptors=patches,
                     response=quality.reshape(-1).astype(np.float32))


def _no_corners(patch_size_px: int) -> Keypoints:
    return Keypoints(np.zeros((0, 2)), np.zeros((0, patch_size_px * patch_size_px), np.float32),
                     np.zeros(0, np.float32))


def check_image(image: npt.ArrayLike, mask: npt.ArrayLike | None
                ) -> tuple[GreyImage, BoolImage | None]:
    """``image`` as a contiguous (H, W) uint8 array and ``mask`` as (H, W) bool, checked.

    Raises:
        ShapeError: ``image`` is not 2-D, or ``mask`` differs from it in shape.
        TypeError: ``image`` is not uint8 or ``mask`` is not bool.
    """
    image = np.ascontiguousarray(image)
    check_shape("image", image.shape, (None, None))
    if image.dtype != np.uint8:
        raise TypeError(f"image: expected dtype uint8, got {image.dtype}")
    if mask is None:
        return image, None
    mask = np.asarray(mask)
    check_shape("mask", mask.shape, image.shape)
    if mask.dtype != np.bool_:
        raise TypeError(f"mask: expected dtype bool, got {mask.dtype}")
    return image, mask


def refine_subpixel(image: GreyImage, pixels_xy: npt.ArrayLike, half_window_px: int
                    ) -> PixelsXY:
    """Corners moved to their sub-pixel positions (``cv2.cornerSubPix``, Förstner 1987).

    Args:
        image: (H, W) uint8.
        pixels_xy: (N, 2) corner positions, px.
        half_window_px: half side of the window; 0 keeps the positions. A corner whose
            refinement would move it farther than this keeps its position.

    Returns:
        (N, 2) float64 px.
    """
    corners = np.ascontiguousarray(pixels_xy, dtype=np.float32).reshape(-1, 1, 2)
    if half_window_px > 0 and len(corners):
        win = (half_window_px, half_window_px)
        corners = cv2.cornerSubPix(image, corners, win, (-1, -1), _SUBPIX_CRITERIA)
    return corners.reshape(-1, 2).astype(np.float64)


def allowed_centres(
    shape: tuple[int, ...], margin: int, mask: BoolImage | None
) -> npt.NDArray[np.uint8] | None:
    """The uint8 mask of pixels whose (2 margin + 1)^2 neighbourhood is valid; None if none are.

    ``mask`` is (H, W) bool, already checked.
    """
    height, width = shape
    if height <= 2 * margin or width <= 2 * margin:
        return None
    if mask is None:
        allowed = np.zeros(shape, dtype=np.uint8)
        allowed[margin:height - margin, margin:width - margin] = 255
        return allowed
    # Erosion with a zero border: a pixel survives iff its whole neighbourhood is
    # inside both the mask and the image.
    kernel = np.ones((2 * margin + 1, 2 * margin + 1), dtype=np.uint8)
    allowed = cv2.erode(mask.view(np.uint8) * np.uint8(255), kernel,
                        borderType=cv2.BORDER_CONSTANT, borderValue=0)
    return allowed if cv2.countNonZero(allowed) > 0 else None


def _normalised_patches(
    image: GreyImage, rows: npt.NDArray[np.intp], cols: npt.NDArray[np.intp], side: int
) -> Patches:
    """Gather (N, side*side) patches centred at (rows, cols), zero-mean and unit-norm.

    ZNCC(p, q) = sum((p - mean p)(q - mean q)) / (|p - mean p| |q - mean q|), so
    with rows normalised here it is a dot product. Flat patches (zero variance)
    become all-zero rows, whose score with anything is 0.
    """
    width = image.shape[1]
    offsets = np.arange(side) - side // 2
    flat_offsets = (offsets[:, None] * width + offsets[None, :]).reshape(-1)
    centres = rows * width + cols
    patches = image.reshape(-1)[centres[:, None] + flat_offsets].astype(np.float32)
    patches -= patches.mean(axis=1, keepdims=True)
    norms = np.linalg.norm(patches, axis=1, keepdims=True)
    patches /= np.where(norms > _FLAT_NORM, norms, np.inf)
    return patches
