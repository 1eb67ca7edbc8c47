"""Synthetic image pairs with a known homography, for tests and benchmarks of matching.

A pair is a random texture (smooth multi-octave noise plus random filled polygons,
which give corners at all angles) seen twice: image B is image A warped by a known
homography ``H_b_a`` (pixels of A to pixels of B), with a global gain and offset
(the simulator's illumination changes) and independent Gaussian noise on each image.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.errors import check_shape

Homography = npt.NDArray[np.float64]
"""(3, 3) float64 homography between pixel coordinates, defined up to scale."""

#: Octaves of the smooth noise: cell size, px, and amplitude, grey levels.
_NOISE_OCTAVES = ((4, 25.0), (16, 25.0), (64, 25.0))
#: Polygons per megapixel, their vertex count range and their radius range, px.
_POLYGONS_PER_MPX = 300
_POLYGON_VERTICES = (3, 7)
_POLYGON_RADIUS_PX = (6.0, 45.0)
#: Grey-level offset of polygons relative to the background, +- this.
_POLYGON_CONTRAST = 60.0


@dataclass(frozen=True, slots=True, eq=False)
class ImagePair:
    """Two views of one texture related by a known homography.

    Attributes:
        image_a: (H, W) uint8.
        image_b: (H, W) uint8, ``image_b(H_b_a p) ~ gain * image_a(p) + offset``.
        H_b_a: (3, 3) float64, maps pixels of A to pixels of B.
    """

    image_a: npt.NDArray[np.uint8]
    image_b: npt.NDArray[np.uint8]
    H_b_a: Homography


def texture(
    rng: np.random.Generator, width: int = 800, height: int = 600
) -> npt.NDArray[np.float32]:
    """A random texture rich in corners, float32 grey levels around 128 (not clipped).

    Args:
        rng: source of all randomness.
        width: image width, px.
        height: image height, px.

    Returns:
        (height, width) float32.
    """
    image = np.full((height, width), 128.0, dtype=np.float32)
    for cell, amplitude in _NOISE_OCTAVES:
        coarse = rng.standard_normal((height // cell + 3, width // cell + 3)).astype(np.float32)
        fine = cv2.resize(coarse, ((width // cell + 3) * cell, (height // cell + 3) * cell),
                          interpolation=cv2.INTER_CUBIC)
        image += amplitude * fine[cell:cell + height, cell:cell + width]
    for _ in range(max(1, round(_POLYGONS_PER_MPX * width * height / 1e6))):
        n_vertices = int(rng.integers(*_POLYGON_VERTICES, endpoint=True))
        angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, n_vertices))
        radii = rng.uniform(*_POLYGON_RADIUS_PX, n_vertices)
        centre = rng.uniform((0.0, 0.0), (width, height))
        vertices = centre + radii[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
        cv2.fillPoly(image, [np.rint(vertices).astype(np.int32)],
                     float(rng.uniform(-_POLYGON_CONTRAST, _POLYGON_CONTRAST)) + 128.0)
    return image


def similarity_homography(
    shift_xy: tuple[float, float], rotation_rad: float = 0.0, scale: float = 1.0,
    centre_xy: tuple[float, float] = (400.0, 300.0), tilt: tuple[float, float] = (0.0, 0.0),
) -> Homography:
    """H_b_a of a rotation and scaling about ``centre_xy``, then a shift, then a perspective tilt.

    Args:
        shift_xy: translation, px.
        rotation_rad: rotation, rad (positive turns x towards y, i.e. clockwise on screen).
        scale: isotropic scale factor.
        centre_xy: fixed point of the rotation and scaling, px.
        tilt: the homography's bottom-row terms (h31, h32), 1/px.

    Returns:
        (3, 3) float64 with H[2, 2] = 1.
    """
    c, s = scale * np.cos(rotation_rad), scale * np.sin(rotation_rad)
    A = np.array([[c, -s], [s, c]])
    centre = np.asarray(centre_xy, dtype=np.float64)
    H = np.eye(3)
    H[:2, :2] = A
    H[:2, 2] = centre - A @ centre + np.asarray(shift_xy, dtype=np.float64)
    H[2, :2] = tilt
    return H


def transform_pixels(
    H_b_a: Homography, pixels_a_xy: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Map (N, 2) pixels of A to (N, 2) pixels of B through a homography."""
    check_shape("H_b_a", np.shape(H_b_a), (3, 3))
    check_shape("pixels_a_xy", np.shape(pixels_a_xy), (None, 2))
    homogeneous = np.column_stack([pixels_a_xy, np.ones(len(pixels_a_xy))]) @ np.asarray(H_b_a).T
    return homogeneous[:, :2] / homogeneous[:, 2:]


def warped_pair(
    rng: np.random.Generator, H_b_a: Homography, width: int = 800, height: int = 600,
    noise_sigma: float = 2.0, gain: float = 1.0, offset: float = 0.0,
) -> ImagePair:
    """A random texture and its view through ``H_b_a``, with illumination change and noise.

    Args:
        rng: source of all randomness.
        H_b_a: (3, 3) maps pixels of A to pixels of B.
        width: image width, px.
        height: image height, px.
        noise_sigma: std of the Gaussian noise added to each image, grey levels.
        gain: multiplies image B's grey levels.
        offset: is added to image B's grey levels.

    Returns:
        The pair; B's pixels that see outside A are filled by reflecting A.
    """
    check_shape("H_b_a", np.shape(H_b_a), (3, 3))
    base = texture(rng, width, height)
    seen = cv2.warpPerspective(base, np.asarray(H_b_a, dtype=np.float64), (width, height),
                               flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    image_a = base + rng.normal(0.0, noise_sigma, base.shape)
    image_b = gain * seen + offset + rng.normal(0.0, noise_sigma, base.shape)
    return ImagePair(
        image_a=np.clip(np.rint(image_a), 0, 255).astype(np.uint8),
        image_b=np.clip(np.rint(image_b), 0, 255).astype(np.uint8),
        H_b_a=np.asarray(H_b_a, dtype=np.float64),
    )
