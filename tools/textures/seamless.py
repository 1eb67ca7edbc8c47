"""Making a photograph tile seamlessly, and measuring how well a picture tiles."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

GreyImage = npt.NDArray[np.uint8]  # (H, W) uint8


def make_seamless(image: GreyImage, band: float = 0.25) -> GreyImage:
    """``image`` cross-faded with itself rolled by half its size, so its repeats join.

    Near the borders the result is the rolled copy (whose wrap-around is the middle of
    the original, continuous), in the middle it is the original (which hides the rolled
    copy's seam); over a band of ``band`` times the side they are blended with weights
    w and 1 - w normalised by sqrt(w^2 + (1 - w)^2), which keeps the contrast of two
    unrelated textures instead of halving their variance in the middle of the band.

    Args:
        image: (H, W) uint8.
        band: width of the blend, as a fraction of each side (0 < band <= 0.5).

    Returns:
        (H, W) uint8 that wraps around without a seam.
    """
    h, w = image.shape
    original = image.astype(np.float64)
    rolled = np.roll(original, (h // 2, w // 2), axis=(0, 1))
    mean = original.mean()

    def ramp(n: int) -> npt.NDArray[np.float64]:
        d = np.minimum(np.arange(n) + 0.5, n - 0.5 - np.arange(n))  # to the nearest border
        return np.clip(d / (band * n), 0.0, 1.0)

    weight = np.minimum(ramp(h)[:, None], ramp(w)[None, :])
    norm = np.sqrt(weight**2 + (1.0 - weight) ** 2)
    blended = mean + (weight * (original - mean) + (1.0 - weight) * (rolled - mean)) / norm
    return np.clip(np.rint(blended), 0, 255).astype(np.uint8)


def seam_ratio(image: GreyImage) -> float:
    """How abrupt the picture's wrap-around seams are: <= 1 is no worse than inside.

    Per direction, the mean absolute step across the seam (last column to first, last
    row to first) over the largest mean absolute step between two neighbouring rows
    (columns) inside the picture; the larger of the two directions. A seam is visible
    when it is more abrupt than any line inside; a pattern whose own lines (grout,
    stripes) fall on the border has a seam as abrupt as those lines, ratio ~1.
    """
    im = image.astype(np.float64)
    ratios = []
    for axis in (0, 1):
        inside = np.abs(np.diff(im, axis=axis)).mean(axis=1 - axis).max()
        seam = np.abs(np.take(im, 0, axis=axis) - np.take(im, -1, axis=axis)).mean()
        ratios.append(seam / max(inside, 1e-9))
    return float(max(ratios))
