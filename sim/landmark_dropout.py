"""Scene change between teach and repeat: a random fraction of the landmarks removed.

Posters come down and furniture moves between the day a route is taught and the
day it is repeated; the robot must still follow it (issue 4, ``--landmark-dropout``).
"""

from __future__ import annotations

import numpy as np

from sim.landmarks import LandmarkField


def drop_landmarks(
    field: LandmarkField, fraction: float, rng: np.random.Generator
) -> LandmarkField:
    """The field without a random ``fraction`` of its landmarks (the others keep their ids).

    Args:
        field: the landmarks.
        fraction: share to remove, in [0, 1]; round(fraction * N) are removed.
        rng: picks which.

    Raises:
        ValueError: ``fraction`` is outside [0, 1].
    """
    if not 0.0 <= fraction <= 1.0:
        raise ValueError(f"fraction must be in [0, 1], got {fraction}")
    n = len(field)
    removed = rng.choice(n, size=round(fraction * n), replace=False)
    keep = np.setdiff1d(np.arange(n), removed)
    return LandmarkField(
        ids=field.ids[keep].copy(),
        positions_w=field.positions_w[keep].copy(),
        normals_w=field.normals_w[keep].copy(),
        surface=field.surface[keep].copy(),
        sizes_m=field.sizes_m[keep].copy(),
        textures=field.textures[keep].copy(),
    )
