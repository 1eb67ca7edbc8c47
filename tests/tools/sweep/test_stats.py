"""The report's statistics against published values."""

from __future__ import annotations

import math

import pytest

from tools.sweep.stats import distance_per_failure, empirical_cdf, wilson_interval


@pytest.mark.parametrize(("successes", "trials", "low", "high"), [
    # Brown, Cai and DasGupta (2001) and Newcombe (1998), Table I: 81/263 -> 0.2553, 0.3662
    (81, 263, 0.2553, 0.3662),
    (8, 10, 0.4902, 0.9433),
    (0, 10, 0.0, 0.2775),
    (10, 10, 0.7225, 1.0),
    (50, 100, 0.4038, 0.5962),
    (1, 1, 0.2065, 1.0),
])
def test_wilson_interval_known_values(successes: int, trials: int, low: float,
                                      high: float) -> None:
    rate = wilson_interval(successes, trials)
    assert (round(rate.low, 4), round(rate.high, 4)) == (low, high)
    assert rate.value == successes / trials


def test_wilson_without_trials_is_everything_and_bad_counts_are_refused() -> None:
    rate = wilson_interval(0, 0)
    assert (rate.low, rate.high) == (0.0, 1.0) and math.isnan(rate.value)
    with pytest.raises(ValueError, match="successes <= trials"):
        wilson_interval(3, 2)


@pytest.mark.parametrize(("failures", "rate_low", "rate_high"), [
    # Garwood's exact 95 % limits of a Poisson count (e.g. Ulm 1990, Table 1)
    (0, 0.0, 3.689),
    (1, 0.0253, 5.572),
    (5, 1.6235, 11.668),
])
def test_distance_per_failure_inverts_the_exact_poisson_limits(
        failures: int, rate_low: float, rate_high: float) -> None:
    found = distance_per_failure(10.0, failures)
    assert found.low_km == pytest.approx(10.0 / rate_high, rel=1e-3)
    if failures:
        assert found.value_km == 10.0 / failures
        assert found.high_km == pytest.approx(10.0 / rate_low, rel=1e-3)
    else:
        assert math.isinf(found.value_km) and math.isinf(found.high_km)


def test_empirical_cdf_steps() -> None:
    x, y = empirical_cdf([3.0, 1.0, 2.0, 2.0])
    assert x.tolist() == [1.0, 2.0, 2.0, 3.0] and y.tolist() == [0.25, 0.5, 0.75, 1.0]
