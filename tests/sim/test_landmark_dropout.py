"""drop_landmarks: a random share of the landmarks removed between teach and repeat."""

from __future__ import annotations

import numpy as np
import pytest

from sim.landmark_dropout import drop_landmarks
from sim.landmarks import generate_landmarks
from sim.world import load_world


@pytest.fixture(scope="module")
def field():
    return generate_landmarks(load_world("lab"), np.random.default_rng(0))


@pytest.mark.parametrize("fraction", [0.0, 0.3, 1.0])
def test_removes_the_fraction_and_keeps_the_rest_unchanged(field, fraction: float) -> None:
    kept = drop_landmarks(field, fraction, np.random.default_rng(1))
    assert len(kept) == len(field) - round(fraction * len(field))
    rows = np.searchsorted(field.ids, kept.ids)
    assert np.array_equal(field.ids[rows], kept.ids)
    assert np.array_equal(field.positions_w[rows], kept.positions_w)
    assert np.array_equal(field.textures[rows], kept.textures)


@pytest.mark.parametrize("fraction", [-0.1, 1.5, float("nan")])
def test_rejects_a_fraction_outside_0_1(field, fraction: float) -> None:
    with pytest.raises(ValueError, match=r"fraction must be in \[0, 1\]"):
        drop_landmarks(field, fraction, np.random.default_rng(1))
